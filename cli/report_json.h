// polyheal CLI — JSON pieces shared by the repair commands' reports.
#pragma once

#include <nlohmann/json.hpp>

#include "polyheal/inspect/report.h"

namespace polyheal::cli {

inline nlohmann::json topology_json(const SurfaceTopology& t) {
  return {{"euler_characteristic", t.euler}, {"components", t.components}, {"boundary_loops", t.boundary_loops},
          {"manifold", t.manifold}};
}

}  // namespace polyheal::cli
