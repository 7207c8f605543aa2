// polyheal — writing meshes.
//
// Doubles are written in their shortest round-trip form (std::to_chars), so
// reading the file back yields the same bits; binary PLY stores doubles as
// float64. STL can only hold float32: writing STL rounds, and the returned
// WriteInfo says so (certify-after-rounding then checks what was written).
//
// Writes are atomic: a temporary file in the target directory, flushed, then
// renamed over the target. On any failure the target is untouched.
#pragma once

#include <string>

#include "polyheal/io/read.h"
#include "polyheal/mesh/soup.h"

namespace polyheal {

struct WriteOptions {
  bool ascii = false;            // STL and PLY: ASCII instead of binary
  bool allow_overwrite = false;  // replace an existing file at the target path
};

struct WriteInfo {
  Format format = Format::off;
  bool coordinates_rounded = false;  // true when the format could not hold every double (STL)
  std::size_t bytes = 0;
};

/// The float nearest to v (ties to even), as a double: what an STL file
/// holds of the coordinate v.
double nearest_float(double v);
/// Each coordinate of p so.
Point3d nearest_float(const Point3d& p);

/// Serialises `soup` in `format` (no file system access).
std::string serialize_soup(const Soup& soup, Format format, bool ascii, bool* rounded = nullptr);

/// `soup` in TetGen's .smesh format (nodes, facets, no holes or regions),
/// coordinates in shortest round-trip form: what `tetgen -p` reads.
std::string serialize_smesh(const Soup& soup);

/// Writes `soup` to `path` atomically (format from the extension). Throws
/// OutputError when the target exists and overwriting was not allowed, or on
/// an I/O failure; the target is then untouched.
WriteInfo write_soup(const Soup& soup, const std::string& path, const WriteOptions& options = {});

/// Writes `data` to `path` atomically (a temporary file in the target
/// directory, fsync, rename): reports, certificates, provenance files.
/// Throws OutputError as write_soup does.
void write_file_atomically(const std::string& path, const std::string& data, bool allow_overwrite);

/// Throws OutputError unless `path` can take an output: not a directory, not
/// an existing file unless `allow_overwrite`, and (with `mesh`) an extension
/// naming a mesh format. The writers check it; commands check it again before
/// their work, so that a long repair does not end in a refusal.
void check_output_path(const std::string& path, bool allow_overwrite, bool mesh = false);

/// Throws OutputError when `output` names the same file as `input`, unless
/// `allow` is set: a repair must never clobber its input by accident.
void refuse_to_clobber(const std::string& input, const std::string& output, bool allow);

}  // namespace polyheal
