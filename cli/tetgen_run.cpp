#include "tetgen_run.h"

#include <stdlib.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "polyheal/io/write.h"

namespace polyheal::cli {

bool tetgen_installed() {
  static const bool installed = std::system("command -v tetgen >/dev/null 2>&1") == 0;
  return installed;
}

TetgenRun run_tetgen(const Soup& soup, const std::string& switches, int time_limit_s) {
  TetgenRun run;
  if (!tetgen_installed()) {
    run.output = "tetgen is not installed";
    return run;
  }
  char dir[] = "/tmp/polyheal-tetgen-XXXXXX";
  if (!mkdtemp(dir)) {
    run.output = "cannot make a temporary directory";
    return run;
  }
  // A throwaway copy in our own directory: no atomic write (fsync) needed.
  if (!(std::ofstream(std::string(dir) + "/mesh.smesh", std::ios::binary) << serialize_smesh(soup))) {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    run.output = std::string("cannot write a temporary file in ") + dir;
    return run;
  }
  const std::string cmd = "cd '" + std::string(dir) + "' && timeout " + std::to_string(time_limit_s) + " tetgen " +
                          switches + " mesh.smesh 2>&1";
  const auto t0 = std::chrono::steady_clock::now();
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[4096];
    while (std::size_t n = std::fread(buf, 1, sizeof buf, p)) run.output.append(buf, n);
    const int st = pclose(p);
    run.ran = true;
    run.status = st == -1 ? -1 : WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  return run;
}

}  // namespace polyheal::cli
