// polyheal CLI — progress on stderr, only when stderr is a terminal.
#pragma once

#include <chrono>
#include <mutex>

#include "polyheal/observer.h"

namespace polyheal::cli {

class TtyProgress : public Observer {
 public:
  TtyProgress();
  ~TtyProgress() override;
  void stage(const char* name) override;
  /// Clears the progress line; later stages print nothing.
  void finish();

 private:
  std::mutex mutex_;  // stages arrive from concurrent passes
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace polyheal::cli
