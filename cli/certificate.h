// polyheal CLI — certificates: what was checked on a written file, bound to
// its bytes by SHA-256, so that `polyheal check FILE --certificate C.json`
// can confirm later (or elsewhere) that the file is the one certified and
// that the checks still come out the same.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "polyheal/inspect/report.h"
#include "polyheal/io/sha256.h"
#include "polyheal/io/write.h"
#include "report_json.h"

namespace polyheal::cli {

inline constexpr const char* kVersion = "0.1.0";

/// The certificate of `output` (as written; `out` its inspection), produced
/// from `input` with `parameters`; `extra` (an object) is merged in.
inline nlohmann::json make_certificate(const std::string& command, const std::string& input, const std::string& output,
                                       const Report& out, const nlohmann::json& parameters,
                                       const nlohmann::json& extra = nlohmann::json::object()) {
  nlohmann::json c = {{"schema", "polyheal.certificate/1"},
                      {"polyheal_version", kVersion},
                      {"command", command},
                      {"input", {{"path", input}, {"sha256", sha256_file(input)}}},
                      {"output", {{"path", output}, {"sha256", sha256_file(output)}}},
                      {"parameters", parameters},
                      {"checks", checks_json(out)}};
  for (auto it = extra.begin(); it != extra.end(); ++it) c[it.key()] = it.value();
  return c;
}

inline void write_certificate(const std::string& path, const nlohmann::json& c, bool overwrite) {
  write_file_atomically(path, c.dump(2) + "\n", overwrite);
}

}  // namespace polyheal::cli
