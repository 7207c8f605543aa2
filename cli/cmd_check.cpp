// polyheal check FILE — the exact oracle as a command.
#include <chrono>
#include <functional>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "report_json.h"
#include "polyheal/inspect/report.h"
#include "polyheal/io/read.h"
#include "progress.h"
#include "tetgen_run.h"
#include "certificate.h"
#include "polyheal/mesh/errors.h"
#include <filesystem>
#include <fstream>
#include <cstdlib>
#include "polyheal/io/write.h"

namespace polyheal::cli {
namespace {

struct CheckArgs {
  std::string file, certificate;
  bool json = false, list = false, tetgen_ready = false, sequential = false, tetgen = false;
  InspectOptions inspect;
};

nlohmann::json edges_json(const std::vector<EdgeRef>& edges) {
  auto a = nlohmann::json::array();
  for (const EdgeRef& e : edges) a.push_back({{"vertices", {e.a, e.b}}, {"faces", e.faces}});
  return a;
}
nlohmann::json pairs_json(const std::vector<FacePair>& pairs) {
  auto a = nlohmann::json::array();
  for (const FacePair& p : pairs) a.push_back({p.first, p.second});
  return a;
}

nlohmann::json near_edges_json(const std::vector<VertexNearEdge>& near) {
  auto a = nlohmann::json::array();
  for (const VertexNearEdge& v : near) a.push_back({{"vertex", v.vertex}, {"edge", {v.a, v.b}}});
  return a;
}

nlohmann::json edge_pairs_json(const std::vector<EdgeNearEdge>& near) {
  auto a = nlohmann::json::array();
  for (const EdgeNearEdge& p : near) a.push_back({p.e, p.f});
  return a;
}

nlohmann::json near_faces_json(const std::vector<VertexNearFace>& near) {
  auto a = nlohmann::json::array();
  for (const VertexNearFace& v : near) a.push_back({{"vertex", v.vertex}, {"face", v.face}});
  return a;
}

nlohmann::json to_json(const CheckArgs& args, const Report& r, double read_s, double total_s) {
  using nlohmann::json;
  json j = {
      {"schema", "polyheal.check/1"},
      {"file", args.file},
      {"certified_clean", r.certified_clean()},
      {"tetgen_ready", r.vertices_near_edges_checked || !r.certified_clean() ? json(r.tetgen_ready())
                                                                             : json(nullptr)},  // null: not decided
      {"counts",
       {{"vertices", r.vertices},
        {"faces", r.faces},
        {"non_triangle_faces", r.non_triangle_faces},
        {"components", r.components},
        {"isolated_vertices", r.isolated_vertices},
        {"merged_identical_vertices", r.merged_identical_vertices}}},
      {"topology",
       {{"closed", r.closed},
        {"manifold", r.manifold},
        {"oriented", r.oriented},
        {"boundary_edges", r.boundary_edges.size()},
        {"boundary_loops", r.boundary_loops},
        {"nonmanifold_edges", r.nonmanifold_edges.size()},
        {"nonmanifold_vertices", r.nonmanifold_vertices.size()},
        {"misoriented_edges", r.misoriented_edges.size()},
        {"duplicate_faces", r.duplicate_faces.size()}}},
      {"geometry",
       {{"degenerate_faces", r.degenerate_faces.size()},
        {"caps", r.caps.size()},
        {"needles", r.needles.size()},
        {"self_intersecting_pairs", r.self_intersections.size()},
        {"crack_pairs", r.crack_pairs},
        {"crack_vertex_pairs", r.crack_vertex_pairs},
        {"crack_distance", args.inspect.crack_ratio * bbox_diagonal(r)},
        {"cap_angle", args.inspect.cap_angle},
        {"needle_angle", args.inspect.needle_angle}}},
      {"tetgen",
       {{"sharp_folds", r.sharp_folds.size()},
        {"nearly_degenerate_faces", r.nearly_degenerate_faces.size()},
        {"vertices_near_edges",
         r.vertices_near_edges_checked ? json(r.vertices_near_edges.size()) : json(nullptr)},  // null: not looked for
        {"close_vertices", r.vertices_near_edges_checked ? json(r.close_vertices.size()) : json(nullptr)},
        {"edges_near_edges", r.vertices_near_edges_checked ? json(r.edges_near_edges.size()) : json(nullptr)},
        {"vertices_near_faces", r.vertices_near_edges_checked ? json(r.vertices_near_faces.size()) : json(nullptr)},
        {"flip_hazards", r.vertices_near_edges_checked ? json(r.flip_hazards.size()) : json(nullptr)},
        {"fold_angle", args.inspect.tetgen_fold_angle},
        {"facet_angle", args.inspect.tetgen_facet_angle},
        {"epsilon", args.inspect.tetgen_epsilon}}},
      {"shape",
       {{"signed_volume", r.signed_volume},
        {"volume_sign", r.volume_sign},
        {"inward_components", r.inward_components},
        {"inside_out_components", r.nesting_checked ? json(r.inside_out_components) : json(nullptr)},
        {"cavities", r.nesting_checked ? json(r.cavities) : json(nullptr)},
        {"bbox", {{"min", r.bbox_min}, {"max", r.bbox_max}}}}},
      {"seconds",
       {{"read", read_s},
        {"topology", r.seconds_topology},
        {"shape", r.seconds_shape},
        {"self_intersections", r.seconds_self_intersections},
        {"total", total_s}}},
  };
  if (args.list)
    j["lists"] = {{"degenerate_faces", r.degenerate_faces},
                  {"caps", r.caps},
                  {"needles", r.needles},
                  {"self_intersecting_pairs", pairs_json(r.self_intersections)},
                  {"boundary_edges", edges_json(r.boundary_edges)},
                  {"nonmanifold_edges", edges_json(r.nonmanifold_edges)},
                  {"nonmanifold_vertices", r.nonmanifold_vertices},
                  {"misoriented_edges", edges_json(r.misoriented_edges)},
                  {"duplicate_faces", r.duplicate_faces},
                  {"sharp_folds", pairs_json(r.sharp_folds)},
                  {"nearly_degenerate_faces", r.nearly_degenerate_faces},
                  {"vertices_near_edges", near_edges_json(r.vertices_near_edges)},
                  {"close_vertices", r.close_vertices},
                  {"edges_near_edges", edge_pairs_json(r.edges_near_edges)},
                  {"vertices_near_faces", near_faces_json(r.vertices_near_faces)},
                  {"flip_hazards", pairs_json(r.flip_hazards)}};
  return j;
}

template <class T>
void print_list(const char* title, const std::vector<T>& items, const std::function<std::string(const T&)>& show) {
  if (items.empty()) return;
  std::printf("  %s:", title);
  for (const T& x : items) std::printf(" %s", show(x).c_str());
  std::printf("\n");
}

void print_text(const CheckArgs& args, const Report& r, double total_s) {
  auto yes = [](bool b) { return b ? "yes" : "no"; };
  std::printf("%s\n", args.file.c_str());
  std::printf("  %zu vertices, %zu faces (%zu non-triangle), %zu component%s, %zu isolated vertices, %zu merged duplicates\n",
              r.vertices, r.faces, r.non_triangle_faces, r.components, r.components == 1 ? "" : "s",
              r.isolated_vertices, r.merged_identical_vertices);
  std::printf("  closed %s, manifold %s, oriented %s; boundary edges %zu in %zu loops, non-manifold edges %zu, "
              "non-manifold vertices %zu, misoriented edges %zu, duplicate faces %zu\n",
              yes(r.closed), yes(r.manifold), yes(r.oriented), r.boundary_edges.size(), r.boundary_loops,
              r.nonmanifold_edges.size(), r.nonmanifold_vertices.size(), r.misoriented_edges.size(),
              r.duplicate_faces.size());
  std::printf("  exact: %zu degenerate faces, %zu caps (>%g deg), %zu needles (<%g deg), %zu self-intersecting pairs\n",
              r.degenerate_faces.size(), r.caps.size(), args.inspect.cap_angle, r.needles.size(),
              args.inspect.needle_angle, r.self_intersections.size());
  if (r.crack_pairs)
    std::printf("    %zu of the pairs meet at %zu pairs of corners closer than %g (%g of the diagonal) but not welded:\n"
                "    cracks a CAD export's rounding leaves; `polyheal degenerate` and `polyheal repair` weld them\n",
                r.crack_pairs, r.crack_vertex_pairs, args.inspect.crack_ratio * bbox_diagonal(r), args.inspect.crack_ratio);
  const bool looked = r.vertices_near_edges_checked;
  const std::string near = looked ? std::to_string(r.vertices_near_edges.size()) : std::string("(not looked for: --tetgen-ready)");
  const std::string close = looked ? std::to_string(r.close_vertices.size()) : std::string("(not looked for)");
  const std::string edges = looked ? std::to_string(r.edges_near_edges.size()) : std::string("(not looked for)");
  const std::string faces = looked ? std::to_string(r.vertices_near_faces.size()) : std::string("(not looked for)");
  const std::string flips = looked ? std::to_string(r.flip_hazards.size()) : std::string("(not looked for)");
  std::printf("  tetgen tolerances: %zu sharp folds (<%g deg), %zu nearly degenerate faces, %s vertices nearly on an "
              "edge, %s vertex pairs, %s edge pairs and %s vertex-face pairs closer than its shortest edge (eps %g x "
              "diagonal), %s face pairs it merges (>%g deg) whose flip cuts another face\n",
              r.sharp_folds.size(), args.inspect.tetgen_fold_angle, r.nearly_degenerate_faces.size(), near.c_str(),
              close.c_str(), edges.c_str(), faces.c_str(), args.inspect.tetgen_epsilon, flips.c_str(),
              args.inspect.tetgen_facet_angle);
  if (r.closed && r.oriented) std::printf("  signed volume %.17g\n", r.signed_volume);
  if (const std::string note = inward_note(r); !note.empty()) std::printf("  note: %s\n", note.c_str());

  if (args.list) {
    auto num = [](const std::size_t& x) { return std::to_string(x); };
    auto idx = [](const Index& x) { return std::to_string(x); };
    auto pair = [](const FacePair& p) { return "(" + std::to_string(p.first) + "," + std::to_string(p.second) + ")"; };
    auto edge = [](const EdgeRef& e) { return "(" + std::to_string(e.a) + "," + std::to_string(e.b) + ")"; };
    auto dup = [](const std::array<std::size_t, 2>& d) {
      return "(" + std::to_string(d[0]) + "," + std::to_string(d[1]) + ")";
    };
    print_list<std::size_t>("degenerate faces", r.degenerate_faces, num);
    print_list<std::size_t>("caps", r.caps, num);
    print_list<std::size_t>("needles", r.needles, num);
    print_list<FacePair>("self-intersecting face pairs", r.self_intersections, pair);
    print_list<EdgeRef>("boundary edges", r.boundary_edges, edge);
    print_list<EdgeRef>("non-manifold edges", r.nonmanifold_edges, edge);
    print_list<Index>("non-manifold vertices", r.nonmanifold_vertices, idx);
    print_list<EdgeRef>("misoriented edges", r.misoriented_edges, edge);
    print_list<std::array<std::size_t, 2>>("duplicate faces", r.duplicate_faces, dup);
    print_list<FacePair>("sharp folds", r.sharp_folds, pair);
    print_list<std::size_t>("nearly degenerate faces", r.nearly_degenerate_faces, num);
    print_list<VertexNearEdge>("vertices nearly on an edge (vertex:edge)", r.vertices_near_edges,
                               [](const VertexNearEdge& v) {
                                 return std::to_string(v.vertex) + ":(" + std::to_string(v.a) + "," +
                                        std::to_string(v.b) + ")";
                               });
    print_list<std::array<Index, 2>>("vertex pairs closer than TetGen's shortest edge", r.close_vertices,
                                     [](const std::array<Index, 2>& p) {
                                       return "(" + std::to_string(p[0]) + "," + std::to_string(p[1]) + ")";
                                     });
    print_list<EdgeNearEdge>("edge pairs closer than TetGen's shortest edge", r.edges_near_edges,
                             [](const EdgeNearEdge& p) {
                               return "(" + std::to_string(p.e[0]) + "," + std::to_string(p.e[1]) + "):(" +
                                      std::to_string(p.f[0]) + "," + std::to_string(p.f[1]) + ")";
                             });
    print_list<VertexNearFace>("vertices closer than TetGen's shortest edge to a face (vertex:face)",
                               r.vertices_near_faces, [](const VertexNearFace& v) {
                                 return std::to_string(v.vertex) + ":" + std::to_string(v.face);
                               });
    print_list<FacePair>("face pairs TetGen merges whose flip cuts another face", r.flip_hazards, pair);
  }
  const bool ok = args.tetgen_ready ? r.tetgen_ready() : r.certified_clean();
  if (!ok && args.tetgen_ready && r.certified_clean())
    std::printf("  (`polyheal repair --for tetgen` removes these: short edges collapsed, close parts pushed apart, "
                "folds and slivers collapsed, else the overlay grid where they are)\n");
  std::printf("  => %s (%.3f s)\n",
              ok ? (args.tetgen_ready ? "CERTIFIED CLEAN and TetGen-ready" : "CERTIFIED CLEAN")
                 : (args.tetgen_ready && r.certified_clean() ? "clean, but NOT TetGen-ready" : "DEFECTS FOUND"),
              total_s);
}

/// `check --tetgen`: TetGen's own self-intersection test (`tetgen -d`) on
/// the mesh as read (run_tetgen: a .smesh in a temporary directory).
/// Returns {ran, pairs, line}: pairs -1 when TetGen's output could not be read.
struct TetgenVerdict {
  bool ran = false;
  long pairs = -1;
  std::string line;  // TetGen's own words
};
TetgenVerdict run_tetgen_d(const Soup& soup) {
  TetgenVerdict v;
  const TetgenRun run = run_tetgen(soup, "-d");
  v.ran = run.ran;
  if (!run.ran) {
    v.line = run.output;
    return v;
  }
  const std::string& out = run.output;
  if (out.find("No faces are intersecting.") != std::string::npos) {
    v.pairs = 0;
    v.line = "No faces are intersecting.";
  } else if (const std::size_t at = out.find("Found "); at != std::string::npos) {
    v.pairs = std::strtol(out.c_str() + at + 6, nullptr, 10);
    v.line = out.substr(at, out.find('\n', at) - at);
  } else {
    v.line = "unrecognised tetgen output";
  }
  return v;
}

/// `check FILE --certificate C`: the file's SHA-256 against the
/// certificate's output hash, and each recorded check against the exact
/// inspection now. Returns what differs (empty: it matches), printed unless --json.
std::vector<std::string> confirm_certificate(const CheckArgs& args, const Report& r) {
  std::ifstream in(args.certificate);
  if (!in) throw InputError(args.certificate, "", "cannot open for reading");
  nlohmann::json c;
  try {
    c = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(args.certificate, "byte " + std::to_string(e.byte), "not JSON");
  }
  if (!c.is_object() || c.value("schema", "") != "polyheal.certificate/1" || !c.contains("checks") ||
      !c["checks"].is_object() || !c.contains("output") || !c["output"].contains("sha256"))
    throw InputError(args.certificate, "", "not a polyheal.certificate/1 document");
  std::vector<std::string> mismatches;
  const std::string hash = sha256_file(args.file);
  if (c["output"]["sha256"] != hash) mismatches.push_back("sha256 " + hash + ", certificate says " +
                                                          c["output"]["sha256"].get<std::string>());
  const nlohmann::json now = checks_json(r);
  for (auto it = c["checks"].begin(); it != c["checks"].end(); ++it) {
    if (it.value().is_null()) continue;  // not decided when the certificate was written
    if (!now.contains(it.key())) mismatches.push_back("unknown check '" + it.key() + "'");
    else if (now[it.key()] != it.value())
      mismatches.push_back(it.key() + " is " + now[it.key()].dump() + ", certificate says " + it.value().dump());
  }
  if (!args.json) {
    std::printf("  certificate %s: %s\n", args.certificate.c_str(),
                mismatches.empty() ? "MATCHES (hash and every check)" : "DOES NOT MATCH");
    for (const std::string& m : mismatches) std::printf("    %s\n", m.c_str());
  }
  return mismatches;
}

}  // namespace

void add_check(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* cmd = app.add_subcommand(
      "check", "Inspect a mesh exactly: topology, degenerate faces, caps, needles, self-intersections");
  cmd->footer(
      "Every answer is decided by exact predicates on the file's own coordinates.\n"
      "Reports counts, topology (boundary, non-manifold edges and vertices, orientation,\n"
      "duplicate faces), degenerate faces, caps and needles (Botsch & Kobbelt), every\n"
      "self-intersecting pair (PMP::self_intersections semantics), and what TetGen's\n"
      "tolerances would trip over.\n\n"
      "Exit 0 when the mesh is a certified clean solid boundary (closed, 2-manifold,\n"
      "consistently oriented, no degenerate or duplicate face, no self-intersection),\n"
      "1 when it has defects, 2 on error (bad file or option; one line on stderr).");
  cmd->add_option("FILE", args->file, "mesh file: .off, .obj, .stl (ASCII or binary), .ply")->required();
  cmd->add_flag("--json", args->json, "print one JSON document (schema polyheal.check/1, see README)");
  cmd->add_flag("--list", args->list, "name the offending faces, edges, vertices and pairs");
  cmd->add_flag("--tetgen-ready", args->tetgen_ready,
                "also require what TetGen's tolerances need (no fold below --fold-angle, no nearly degenerate "
                "face, no vertex nearly on an edge it is not on, no two vertices, edges or vertex and face closer "
                "than its shortest edge, no nearly flat pair whose flip cuts another face); exit 1 otherwise");
  cmd->add_option("--cap-angle", args->inspect.cap_angle, "a face with an angle above this is a cap (degrees)")
      ->default_val(175.0)->check(CLI::Range(90.0, 180.0));
  cmd->add_option("--needle-angle", args->inspect.needle_angle,
                  "a face with an angle below this is a needle unless it is a cap (degrees)")
      ->default_val(5.0)->check(CLI::Range(0.0, 60.0));
  cmd->add_option("--fold-angle", args->inspect.tetgen_fold_angle,
                  "TetGen: adjacent faces folded below this angle are 'nearly self-intersecting' (degrees)")
      ->default_val(0.1)->check(CLI::Range(0.0, 90.0));
  cmd->add_flag("--sequential", args->sequential, "do not use threads");
  cmd->add_flag("--tetgen", args->tetgen,
                "also run TetGen's own test (tetgen -d, when installed) and print its verdict beside ours "
                "(does not change the exit code)");
  cmd->add_option("--certificate", args->certificate,
                  "confirm FILE matches this certificate (written by repair --certificate): its SHA-256 and "
                  "every recorded check; exit 1 on any difference");
  cmd->callback([args, &exit_code] {
    const auto t0 = std::chrono::steady_clock::now();
    TtyProgress progress;
    progress.stage("reading");
    const Soup soup = read_soup(args->file);
    const double read_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    args->inspect.parallel = !args->sequential;
    // TetGen's segment test costs a spatial search: when TetGen-readiness is
    // asked for, or a certificate may record it.
    args->inspect.tetgen_segments = args->tetgen_ready || !args->certificate.empty();
    args->inspect.observer = &progress;
    const Report r = inspect(soup, args->inspect);
    const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.finish();
    bool matches = true;
    nlohmann::json j;
    if (args->json) j = to_json(*args, r, read_s, total_s);
    else print_text(*args, r, total_s);
    if (args->tetgen) {
      const TetgenVerdict t = run_tetgen_d(soup);
      if (args->json) {
        j["tetgen"] = {{"ran", t.ran}, {"intersecting_pairs", t.pairs}, {"message", t.line}};
      } else {
        std::printf("  tetgen -d: %s (polyheal: %zu self-intersecting pairs%s)\n", t.line.c_str(),
                    r.self_intersections.size(),
                    t.pairs < 0 ? "" : (t.pairs == 0) == r.self_intersections.empty() ? "; verdicts agree" : "; verdicts DIFFER");
      }
    }
    if (!args->certificate.empty()) {
      const std::vector<std::string> mismatches = confirm_certificate(*args, r);
      matches = mismatches.empty();
      if (args->json) j["certificate"] = {{"path", args->certificate}, {"matches", matches}, {"mismatches", mismatches}};
    }
    if (args->json) std::cout << j.dump(2) << "\n";
    const bool ok = args->tetgen_ready ? r.tetgen_ready() : r.certified_clean();
    exit_code = ok && matches ? kClean : kDefects;
  });
}

}  // namespace polyheal::cli
