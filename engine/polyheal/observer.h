// polyheal — progress and debug hooks, empty by default (STYLE.md habit 11).
#pragma once

namespace polyheal {

/// Passed to long operations. The CLI implements it to draw progress on a
/// TTY; tests and library users leave it out. Hooks may be called from
/// several threads at once (inspect() runs its passes concurrently), so an
/// implementation must be thread-safe.
class Observer {
 public:
  virtual ~Observer() = default;
  virtual void stage(const char* /*name*/) {}
  virtual void progress(double /*fraction in [0, 1]*/) {}
};

}  // namespace polyheal
