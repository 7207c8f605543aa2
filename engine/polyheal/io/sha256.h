// polyheal — SHA-256 of files, for certificates (FIPS 180-4).
#pragma once

#include <string>
#include <string_view>

namespace polyheal {

/// Lower-case hex SHA-256 of `bytes`.
std::string sha256_hex(std::string_view bytes);

/// Lower-case hex SHA-256 of the file at `path` (InputError when it cannot
/// be read).
std::string sha256_file(const std::string& path);

}  // namespace polyheal
