// polyheal — reading meshes. The one place (with write.h) that knows formats.
//
// Every reader yields a polygon soup with the file's coordinates bit for bit
// (doubles parsed with correct rounding, floats widened exactly). Formats:
// OFF (OFF/COFF/NOFF/CNOFF/STOFF headers), OBJ (with `g` groups), STL (ASCII and
// binary, told apart by content, not extension; several ASCII solids become
// groups), PLY (ASCII, binary little and big endian; a scalar face property
// patch_id/patch/face_group/group/part/region/segment/label becomes groups).
// STL triangles are welded on identical coordinates.
//
// Errors: any malformed input throws InputError naming the file, the line
// (text) or byte offset (binary) and the reason. Declared counts are checked
// against the file size before anything is allocated.
#pragma once

#include <string>
#include <string_view>

#include "polyheal/mesh/errors.h"
#include "polyheal/mesh/soup.h"

namespace polyheal {

enum class Format { off, obj, stl, ply };

/// Format from the file name's extension (case-insensitive). Throws InputError
/// for an unknown extension.
Format format_from_path(const std::string& path);

/// Reads `path` (format from its extension; STL flavour from its content).
Soup read_soup(const std::string& path);

/// Parses an in-memory file; `name` is used in error messages only.
Soup parse_soup(std::string_view bytes, Format format, const std::string& name);

}  // namespace polyheal
