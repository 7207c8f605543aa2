// polyheal CLI — what every repair command shares: its file arguments, the
// read (refusing to clobber first), the repair call (an unsupported input is
// an error naming the file) and the write that is read back to be certified.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "polyheal/io/read.h"
#include "polyheal/io/write.h"
#include "polyheal/mesh/errors.h"
#include "progress.h"

namespace polyheal::cli {

struct RepairFiles {
  std::string input, output;
  bool json = false, list = false, ascii = false, overwrite = false;
};

/// IN (`in_help`), -o, --json (naming `schema`), --list (`list_help`; none
/// when empty), --ascii, --overwrite.
inline void add_repair_files(CLI::App* cmd, RepairFiles& f, const std::string& schema, const std::string& list_help,
                             const std::string& in_help = "input mesh (.off, .obj, .stl, .ply): an oriented "
                                                          "2-manifold, open or closed (pinch vertices allowed)") {
  cmd->add_option("IN", f.input, in_help)->required();
  cmd->add_option("-o,--output", f.output, "output mesh; format from the extension")->required();
  cmd->add_flag("--json", f.json, "print one JSON document (schema " + schema + ", see README)");
  if (!list_help.empty()) cmd->add_flag("--list", f.list, list_help);
  cmd->add_flag("--ascii", f.ascii, "STL/PLY output in ASCII");
  cmd->add_flag("--overwrite", f.overwrite, "replace an existing output file (never the input)");
}

/// Parses a length option: "0.01" in model units (into `absolute`) or
/// "0.1%" of the bbox diagonal (into `ratio`, as a fraction).
inline void parse_length(const std::string& option, const std::string& text, double& absolute, double& ratio,
                         bool allow_zero = false) {
  if (text.empty()) return;
  const bool relative = text.back() == '%';
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(relative ? text.substr(0, text.size() - 1) : text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() - (relative ? 1 : 0) || !(v > 0 || (allow_zero && v == 0)))
    throw CLI::ValidationError(option, std::string(allow_zero ? "expected a number >= 0" : "expected a positive number") +
                                           ", optionally followed by %: " + text);
  if (relative) ratio = v / 100.0;
  else absolute = v;
}

/// A count option (unsigned): CLI11 reads "-5" into an unsigned number as
/// a huge one; this says what is wrong instead.
inline const CLI::Validator& count_check() {
  static const CLI::Validator check(
      [](std::string& text) {
        return !text.empty() && text.find_first_not_of("0123456789") == std::string::npos
                   ? std::string()
                   : "expected a whole number >= 0: " + text;
      },
      "");
  return check;
}

/// The output format holds float32 coordinates only (STL): the repairs
/// round their result to floats themselves.
inline bool float_output(const RepairFiles& f) { return format_from_path(f.output) == Format::stl; }

/// Refuses to overwrite the input (or an existing output without
/// --overwrite), then reads the input; `seconds` receives the time taken.
inline Soup read_repair_input(const RepairFiles& f, TtyProgress& progress, double& seconds) {
  const auto t0 = std::chrono::steady_clock::now();
  refuse_to_clobber(f.input, f.output, false);
  check_output_path(f.output, f.overwrite, true);
  progress.stage("reading");
  Soup soup = read_soup(f.input);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return soup;
}

/// Runs `repair()`; an input the repair does not support is an error that
/// names the file.
template <class Repair>
auto run_repair(const RepairFiles& f, Repair repair) -> decltype(repair()) {
  try {
    return repair();
  } catch (const NotManifold& e) {
    throw std::runtime_error(f.input + ": " + e.what() +
                             "; `polyheal repair` makes one (its clean stage drops duplicate faces, "
                             "orients, splits non-manifold edges and vertices, and fills holes)");
  } catch (const UnsupportedInput& e) {
    throw std::runtime_error(f.input + ": " + e.what());
  }
}

/// Writes `soup` to the output (atomically) and returns the file as read
/// back: certify what was written, not what was meant to be written.
/// `replace_own` allows replacing an output this run wrote before.
inline Soup write_and_read_back(const Soup& soup, const RepairFiles& f, bool replace_own = false) {
  WriteOptions wo;
  wo.ascii = f.ascii;
  wo.allow_overwrite = f.overwrite || replace_own;
  write_soup(soup, f.output, wo);
  return read_soup(f.output);
}


/// The last stage of a repair command: writes `soup`, reads the file back,
/// `certify(written)` (returns whether it is certified), then prints the
/// report — `json()` (an nlohmann::json) with --json, else `text()` — and
/// sets the exit code. `seconds` receives the write-and-verify time.
template <class Certify, class Json, class Text>
void finish_repair(const Soup& soup, const RepairFiles& f, TtyProgress& progress, double& seconds, Certify certify,
                   Json json, Text text, int& exit_code) {
  const auto t0 = std::chrono::steady_clock::now();
  progress.stage("writing and verifying");
  const Soup written = write_and_read_back(soup, f);
  const bool certified = certify(written);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.finish();
  if (f.json)
    std::cout << json().dump(2) << "\n";
  else
    text();
  exit_code = certified ? kClean : kDefects;
}

}  // namespace polyheal::cli
