#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace polyheal::cli {

TtyProgress::TtyProgress() : enabled_(::isatty(2) == 1), start_(std::chrono::steady_clock::now()) {}

TtyProgress::~TtyProgress() { finish(); }

void TtyProgress::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (enabled_) std::fprintf(stderr, "\r\033[K");
  enabled_ = false;
}

void TtyProgress::stage(const char* name) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!enabled_) return;
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r\033[K[polyheal %6.2fs] %s ...", t, name);
  std::fflush(stderr);
}

}  // namespace polyheal::cli
