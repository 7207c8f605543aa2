#include "polyheal/mesh/topology.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

#include "polyheal/mesh/union_find.h"

namespace polyheal {

Topology analyze_topology(const Soup& soup) {
  Topology t;
  const std::size_t nf = soup.face_count(), nv = soup.points.size(), nc = soup.indices.size();
  std::vector<std::uint32_t> corner_face(nc);
  for (std::size_t f = 0; f < nf; ++f)
    for (std::size_t c = soup.offsets[f]; c < soup.offsets[f + 1]; ++c) corner_face[c] = static_cast<std::uint32_t>(f);
  auto next = [&](std::size_t c) {
    const std::size_t f = corner_face[c];
    return c + 1 == soup.offsets[f + 1] ? soup.offsets[f] : c + 1;
  };

  // Faces with a repeated vertex index; their repeated edges are skipped below.
  std::vector<char> used(nv, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    FaceView v = soup.face(f);
    bool repeated;
    if (v.size() == 3) {
      repeated = v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
    } else {
      std::vector<Index> sorted(v.begin(), v.end());
      std::sort(sorted.begin(), sorted.end());
      repeated = std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
    }
    if (repeated) t.repeated_index_faces.push_back(f);
    for (Index i : v) used[i] = 1;
  }
  t.isolated_vertices = static_cast<std::size_t>(std::count(used.begin(), used.end(), 0));

  // Bucket halfedges (corners) by their smaller endpoint: linear, cache friendly.
  std::vector<std::size_t> start(nv + 1, 0);
  for (std::size_t c = 0; c < nc; ++c) {
    Index u = soup.indices[c], w = soup.indices[next(c)];
    if (u != w) ++start[std::min(u, w) + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::size_t> bucket(start[nv]);
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t c = 0; c < nc; ++c) {
      Index u = soup.indices[c], w = soup.indices[next(c)];
      if (u != w) bucket[fill[std::min(u, w)]++] = c;
    }
  }
  auto other = [&](std::size_t c) { return std::max(soup.indices[c], soup.indices[next(c)]); };

  // Duplicate triangles share every edge: find them on the edge (a, b) formed
  // by their two smallest vertices, grouping uses by the third vertex.
  std::vector<std::pair<Index, std::size_t>> thirds;
  auto find_duplicate_triangles = [&](auto first, auto last, Index b) {
    thirds.clear();
    for (auto it = first; it != last; ++it) {
      const std::size_t f = corner_face[*it];
      if (soup.offsets[f + 1] - soup.offsets[f] != 3) continue;
      const Index c = soup.indices[next(next(*it))];
      if (c > b) thirds.push_back({c, f});
    }
    if (thirds.size() < 2) return;
    std::sort(thirds.begin(), thirds.end());
    for (std::size_t k = 1; k < thirds.size(); ++k)
      if (thirds[k].first == thirds[k - 1].first) t.duplicate_faces.push_back({thirds[k - 1].second, thirds[k].second});
  };
  UnionFind faces(nf), corners(nc), boundary(nv);
  std::vector<char> on_boundary(nv, 0);
  std::vector<std::size_t> around;  // corner of each face at a given vertex
  for (Index a = 0; a < nv; ++a) {
    auto first = bucket.begin() + static_cast<std::ptrdiff_t>(start[a]);
    auto last = bucket.begin() + static_cast<std::ptrdiff_t>(start[a + 1]);
    std::sort(first, last, [&](std::size_t x, std::size_t y) { return other(x) < other(y); });
    for (auto run = first; run != last;) {
      auto end = run;
      while (end != last && other(*end) == other(*run)) ++end;
      const Index b = other(*run);
      const std::size_t n_uses = static_cast<std::size_t>(end - run);
      if (n_uses >= 2) find_duplicate_triangles(run, end, b);
      ++t.edge_count;
      for (auto it = run + 1; it != end; ++it) faces.unite(corner_face[*run], corner_face[*it]);
      const std::size_t c0 = *run, n0 = next(c0);
      if (n_uses == 2 && soup.indices[c0] != soup.indices[*(run + 1)]) {
        // Two uses, opposite directions: glue the corners at both endpoints into one fan.
        const std::size_t c1 = *(run + 1), n1 = next(c1);
        corners.unite(c0, n1);
        corners.unite(n0, c1);
        t.interior_edges.push_back({a, b, corner_face[c0], corner_face[c1]});
        run = end;
        continue;
      }
      Edge e{a, b, {}};
      for (auto it = run; it != end; ++it)
        e.uses.push_back({corner_face[*it], soup.indices[*it], soup.indices[next(*it)]});
      if (e.uses.size() == 1) {
        boundary.unite(e.a, e.b);
        on_boundary[e.a] = on_boundary[e.b] = 1;
        t.boundary_edges.push_back(std::move(e));
      } else if (e.uses.size() > 2) {
        t.nonmanifold_edges.push_back(std::move(e));
      } else {  // two uses in the same direction: one fan, inconsistently oriented
        const std::size_t c1 = *(run + 1);
        corners.unite(c0, c1);
        corners.unite(n0, next(c1));
        t.misoriented_edges.push_back(std::move(e));
      }
      run = end;
    }
  }

  // A vertex is non-manifold when its corners form more than one fan.
  std::vector<std::size_t> fan_root(nv, SIZE_MAX);
  std::vector<char> flagged(nv, 0);
  for (std::size_t c = 0; c < nc; ++c) {
    const Index v = soup.indices[c];
    const std::size_t r = corners.find(c);
    if (fan_root[v] == SIZE_MAX) fan_root[v] = r;
    else if (fan_root[v] != r && !flagged[v]) {
      flagged[v] = 1;
      t.nonmanifold_vertices.push_back(v);
    }
  }
  std::sort(t.nonmanifold_vertices.begin(), t.nonmanifold_vertices.end());

  for (Index v = 0; v < nv; ++v)
    if (on_boundary[v] && boundary.find(v) == v) ++t.boundary_loops;
  t.face_component.resize(nf);
  std::vector<std::size_t> comp_id(nf, SIZE_MAX);
  for (std::size_t f = 0; f < nf; ++f) {
    const std::size_t r = faces.find(f);
    if (comp_id[r] == SIZE_MAX) comp_id[r] = t.components++;
    t.face_component[f] = comp_id[r];
  }

  // Duplicate polygons and faces repeating an index (rare): identical sorted vertex lists.
  std::vector<std::pair<std::vector<Index>, std::size_t>> keyed;
  for (std::size_t f = 0; f < nf; ++f) {
    FaceView v = soup.face(f);
    const bool repeated = std::binary_search(t.repeated_index_faces.begin(), t.repeated_index_faces.end(), f);
    if (v.size() == 3 && !repeated) continue;  // handled on the edges above
    std::vector<Index> k(v.begin(), v.end());
    std::sort(k.begin(), k.end());
    keyed.push_back({std::move(k), f});
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t i = 1; i < keyed.size(); ++i)
    if (keyed[i].first == keyed[i - 1].first) t.duplicate_faces.push_back({keyed[i - 1].second, keyed[i].second});
  std::sort(t.duplicate_faces.begin(), t.duplicate_faces.end());
  return t;
}

SheetsLeftOut sheets_to_leave_out(const Soup& soup, bool flaps,
                                  const std::function<bool(const std::vector<std::size_t>&)>& may_leave_out) {
  const Topology t = analyze_topology(soup);
  auto sign = [](const EdgeUse& u) { return u.from < u.to ? 1L : -1L; };
  struct Rim {
    long balance = 0;       // uses one way minus the other, by kept faces
    std::size_t uses = 0;   // by kept faces
    std::size_t input_uses = 0;
  };
  std::unordered_map<std::uint64_t, Rim> rims;  // the edges that are not interior
  long total = 0;
  for (const auto* edges : {&t.boundary_edges, &t.nonmanifold_edges, &t.misoriented_edges})
    for (const Edge& e : *edges) {
      Rim& r = rims[undirected_edge_key(e.a, e.b)];
      for (const EdgeUse& u : e.uses) r.balance += sign(u);
      r.uses = r.input_uses = e.uses.size();
      total += std::abs(r.balance);
    }
  SheetsLeftOut result;
  std::vector<std::size_t>& out = result.faces;
  if (total > 0) {
    UnionFind sheet_of(soup.face_count());
    for (const Topology::InteriorEdge& e : t.interior_edges) sheet_of.unite(e.face0, e.face1);
    struct Sheet {
      std::vector<std::size_t> faces;
      std::map<std::uint64_t, std::pair<long, std::size_t>> rim;  // edge -> (net use, uses) by the sheet
      bool done = false;
    };
    std::map<std::size_t, Sheet> by_root;
    for (std::size_t f = 0; f < soup.face_count(); ++f) by_root[sheet_of.find(f)].faces.push_back(f);
    for (const auto* edges : {&t.boundary_edges, &t.nonmanifold_edges, &t.misoriented_edges})
      for (const Edge& e : *edges)
        for (const EdgeUse& u : e.uses) {
          auto& [net, uses] = by_root[sheet_of.find(u.face)].rim[undirected_edge_key(e.a, e.b)];
          net += sign(u);
          ++uses;
        }
    std::vector<Sheet*> order;
    for (auto& [root, sh] : by_root) order.push_back(&sh);
    std::stable_sort(order.begin(), order.end(),
                     [](const Sheet* a, const Sheet* b) { return a->faces.size() < b->faces.size(); });
    // A wall's rim edges have 3+ uses in the input; a flap's rim is free
    // edges and such edges, of which one at least is still used twice by
    // kept faces outside it (what it hangs off is kept).
    auto hangs = [&](const Sheet& sh) {
      bool free = false, held = false;
      for (const auto& [k, use] : sh.rim) {
        const Rim& r = rims[k];
        const std::size_t others = r.uses - use.second;
        if (flaps && others == 0) {
          free = true;
        } else if (r.input_uses >= 3) {
          held = held || others >= 2;
        } else {
          return false;
        }
      }
      return !free || held;
    };
    for (bool progress = true; total > 0 && progress;) {
      progress = false;
      for (Sheet* sh : order) {
        if (sh->done || !hangs(*sh)) continue;
        long gain = 0;
        for (const auto& [k, use] : sh->rim) gain += std::abs(rims[k].balance) - std::abs(rims[k].balance - use.first);
        if (gain <= 0) continue;
        if (may_leave_out && !may_leave_out(sh->faces)) {  // faces: in order, from the loop above
          sh->done = true;
          continue;
        }
        for (const auto& [k, use] : sh->rim) {
          rims[k].balance -= use.first;
          rims[k].uses -= use.second;
        }
        total -= gain;
        out.insert(out.end(), sh->faces.begin(), sh->faces.end());
        sh->done = true;
        progress = true;
      }
    }
  }
  result.imbalance = total;
  if (total > 0) {
    std::uint64_t worst = std::numeric_limits<std::uint64_t>::max();
    for (const auto& [k, r] : rims)
      if (r.balance != 0 && k < worst) {
        worst = k;
        result.unbalanced_by = std::abs(r.balance);
      }
    result.unbalanced_a = Index(worst >> 32);
    result.unbalanced_b = Index(worst & 0xFFFFFFFFu);
  }
  std::sort(out.begin(), out.end());
  return result;
}

}  // namespace polyheal
