// polyheal — error types shared by every layer.
//
// Bad input is one exception type carrying file, position and reason; the CLI
// turns it into a one-line message and exit code 2. "Could not finish" is not
// an exception: it is a status in a result struct.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace polyheal {

/// Malformed or unreadable input. `position` is human readable ("line 12",
/// "byte 84", "header"); empty when the whole file is at fault (missing file).
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string position, std::string reason)
      : std::runtime_error(compose(file, position, reason)),
        file_(std::move(file)), position_(std::move(position)), reason_(std::move(reason)) {}

  const std::string& file() const { return file_; }
  const std::string& position() const { return position_; }
  const std::string& reason() const { return reason_; }

 private:
  static std::string compose(const std::string& f, const std::string& p, const std::string& r) {
    return p.empty() ? f + ": " + r : f + ":" + p + ": " + r;
  }
  std::string file_, position_, reason_;
};

/// Well-formed input that a command does not handle (a non-manifold soup
/// given to a command that needs a mesh). The message names the first
/// problem; the CLI prefixes the file name and exits 2.
class UnsupportedInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The input is not an oriented 2-manifold (pinch vertices aside) and the
/// command needs one: its first problem and how many more. The CLI adds
/// what makes one (`polyheal repair`'s clean stage).
class NotManifold : public UnsupportedInput {
 public:
  explicit NotManifold(const std::vector<std::string>& problems, const std::string& needs = "")
      : UnsupportedInput("not an oriented 2-manifold mesh: " + (problems.empty() ? std::string("?") : problems.front()) +
                         (problems.size() > 1 ? " (and " + std::to_string(problems.size() - 1) + " more problems)" : "") +
                         (needs.empty() ? "" : "; " + needs)) {}
};

/// Failure to write an output file (permissions, disk full, refusal to
/// overwrite the input). The target file is left untouched.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace polyheal
