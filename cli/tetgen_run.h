// polyheal CLI — TetGen itself, run on a surface (Debian's `tetgen`, when it
// is on PATH): `check --tetgen` (its self-intersection test) and `repair --for
// tetgen` (does `tetgen -pQ` mesh the surface?). Our TetGen-readiness test
// (Report::tetgen_ready) is exact about TetGen's documented tolerances but
// cannot predict every failure of its floating-point boundary recovery; the
// run can.
#pragma once

#include <string>

#include "polyheal/mesh/soup.h"

namespace polyheal::cli {

struct TetgenRun {
  bool ran = false;    // tetgen was found and started
  int status = -1;     // its exit status: 0 finished; 124 out of time; 134 aborted
  double seconds = 0;
  std::string output;  // what it printed (stdout and stderr)
};

bool tetgen_installed();

/// `tetgen SWITCHES mesh.smesh` on `soup` (written as .smesh into a temporary
/// directory, removed afterwards: TetGen writes its results beside its
/// input), stopped after `time_limit_s` seconds.
TetgenRun run_tetgen(const Soup& soup, const std::string& switches, int time_limit_s = 600);

}  // namespace polyheal::cli
