// spherechain baker — segmentation dispatch, user region maps, agreement between two segmentations,
// and the helpers the rig and geometry methods share (welded vertex graph, connected limbs).
#include "spherechain/baker/segment.h"

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>
#include <tuple>

#include "segment_internal.h"

namespace spherechain::baker {
namespace segment_detail {

Eigen::Vector3d UpVector(UpAxis axis) {
  switch (axis) {
    case UpAxis::kY: return Eigen::Vector3d::UnitY();
    case UpAxis::kZ: return Eigen::Vector3d::UnitZ();
    case UpAxis::kX: return Eigen::Vector3d::UnitX();
  }
  return Eigen::Vector3d::UnitY();
}

Status CheckMeshForSegmentation(const Mesh& mesh) {
  if (mesh.positions.size() % 3 != 0 || mesh.indices.size() % 3 != 0)
    return MakeError(Error::Code::kInvalidMesh, "segment: positions / indices are not multiples of 3");
  if (mesh.triangle_count() == 0) return MakeError(Error::Code::kInvalidMesh, "segment: the mesh has no triangles");
  const uint32_t nv = mesh.vertex_count();
  for (size_t i = 0; i < mesh.indices.size(); ++i) {
    if (mesh.indices[i] >= nv) {
      return MakeError(Error::Code::kInvalidMesh, "segment: triangle " + std::to_string(i / 3) + " refers to vertex " +
                                                      std::to_string(mesh.indices[i]) + " of " + std::to_string(nv));
    }
  }
  for (float f : mesh.positions) {
    if (!std::isfinite(f)) return MakeError(Error::Code::kInvalidMesh, "segment: non-finite vertex coordinate");
  }
  return Ok{};
}

std::vector<double> TriangleAreas(const Mesh& mesh) {
  const uint32_t nt = mesh.triangle_count();
  std::vector<double> area(nt);
  for (uint32_t t = 0; t < nt; ++t) {
    const Eigen::Vector3d a = Position(mesh, mesh.indices[3 * t]);
    const Eigen::Vector3d b = Position(mesh, mesh.indices[3 * t + 1]);
    const Eigen::Vector3d c = Position(mesh, mesh.indices[3 * t + 2]);
    area[t] = 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

WeldedGraph BuildWeldedGraph(const Mesh& mesh) {
  const uint32_t nv = mesh.vertex_count();
  const uint32_t nt = mesh.triangle_count();
  WeldedGraph g;
  g.rep.resize(nv);
  // Weld every pair of vertices within eps = 1e-6 of the bounding-box diagonal (Chebyshev distance),
  // transitively: each vertex compared with the vertices of the grid cells its eps box touches,
  // clusters by union-find, the lowest index the representative. (A plain quantised key would
  // split two copies of one seam position that straddle a cell boundary: mirrored halves whose seam
  // copies differ in the last bits, parts placed by separate node transforms.)
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (uint32_t v = 0; v < nv; ++v) {
    lo = lo.cwiseMin(Position(mesh, v));
    hi = hi.cwiseMax(Position(mesh, v));
  }
  const double eps = std::max(1e-12, 1e-6 * (nv ? (hi - lo).norm() : 1.0));
  // Cells of 64 eps, sorted (no hash map of lists): the eps box around a vertex almost always lies in
  // its own cell, so a vertex looks at one run of the sorted order, rarely at up to 8.
  const double cell = 64.0 * eps;
  auto key_of = [&](double x) { return static_cast<int64_t>(std::floor(x / cell)); };
  struct Entry {
    std::array<int64_t, 3> key;
    std::array<float, 3> p;
    uint32_t v;
  };
  std::vector<Entry> sorted(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    const float* q = &mesh.positions[3 * size_t(v)];
    sorted[v] = {{key_of(q[0]), key_of(q[1]), key_of(q[2])}, {q[0], q[1], q[2]}, v};
  }
  // Within a cell equal positions are adjacent (then by index): each run of one position is welded at
  // once, and only its first entry is compared with other positions.
  std::sort(sorted.begin(), sorted.end(), [](const Entry& x, const Entry& y) {
    return std::tie(x.key, x.p, x.v) < std::tie(y.key, y.p, y.v);
  });
  std::vector<uint32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto unite = [&](uint32_t x, uint32_t y) {
    const uint32_t a = find(x), b = find(y);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  };
  std::vector<size_t> distinct;  // indices into `sorted` of the first entry of each position
  distinct.reserve(nv);
  for (size_t i = 0; i < sorted.size(); ++i) {
    if (i > 0 && sorted[i].key == sorted[i - 1].key && sorted[i].p == sorted[i - 1].p) {
      unite(sorted[i - 1].v, sorted[i].v);
      continue;
    }
    distinct.push_back(i);
  }
  auto cell_begin = [&](const std::array<int64_t, 3>& k) {
    return std::lower_bound(distinct.begin(), distinct.end(), k,
                            [&](size_t i, const std::array<int64_t, 3>& key) { return sorted[i].key < key; });
  };
  for (size_t i : distinct) {
    const Entry& e = sorted[i];
    int64_t lo_key[3], hi_key[3];
    for (int a = 0; a < 3; ++a) lo_key[a] = key_of(double(e.p[a]) - eps), hi_key[a] = key_of(double(e.p[a]) + eps);
    for (int64_t kx = lo_key[0]; kx <= hi_key[0]; ++kx)
      for (int64_t ky = lo_key[1]; ky <= hi_key[1]; ++ky)
        for (int64_t kz = lo_key[2]; kz <= hi_key[2]; ++kz) {
          const std::array<int64_t, 3> k{kx, ky, kz};
          if (k < e.key) continue;  // each pair of cells once: from the lower cell
          for (auto it = k == e.key ? std::upper_bound(distinct.begin(), distinct.end(), i) : cell_begin(k);
               it != distinct.end() && sorted[*it].key == k; ++it) {
            const Entry& f = sorted[*it];
            double d = 0.0;
            for (int a = 0; a < 3; ++a) d = std::max(d, std::abs(double(f.p[a]) - double(e.p[a])));
            if (d <= eps) unite(e.v, f.v);
          }
        }
  }
  for (uint32_t v = 0; v < nv; ++v) g.rep[v] = find(v);  // the root is the cluster's lowest index
  // CSR adjacency over representatives: rows filled by counting, then each row sorted and deduplicated.
  g.used.assign(nv, 0);
  g.area.assign(nv, 0.0);
  const std::vector<double> tri_area = TriangleAreas(mesh);
  std::vector<uint32_t> fill(size_t(nv) + 1, 0);
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = g.rep[mesh.indices[3 * t + k]];
      const uint32_t b = g.rep[mesh.indices[3 * t + (k + 1) % 3]];
      g.used[a] = 1;
      g.area[a] += tri_area[t] / 3.0;
      if (a == b) continue;
      ++fill[a + 1];
      ++fill[b + 1];
    }
  }
  for (uint32_t v = 0; v < nv; ++v) fill[v + 1] += fill[v];
  std::vector<uint32_t> raw(fill[nv]);
  std::vector<uint32_t> next(fill.begin(), fill.end() - 1);
  for (uint32_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = g.rep[mesh.indices[3 * t + k]];
      const uint32_t b = g.rep[mesh.indices[3 * t + (k + 1) % 3]];
      if (a == b) continue;
      raw[next[a]++] = b;
      raw[next[b]++] = a;
    }
  g.offsets.assign(size_t(nv) + 1, 0);
  g.adj.clear();
  g.adj.reserve(raw.size() / 2);
  for (uint32_t v = 0; v < nv; ++v) {
    const auto first = raw.begin() + fill[v], last = raw.begin() + fill[v + 1];
    std::sort(first, last);
    g.adj.insert(g.adj.end(), first, std::unique(first, last));
    g.offsets[v + 1] = uint32_t(g.adj.size());
  }
  return g;
}

namespace {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t Find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void Unite(uint32_t a, uint32_t b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

/// Same-region triangle pieces: component id per triangle, area and contact per component.
struct Pieces {
  std::vector<uint32_t> of_triangle;
  std::vector<uint8_t> region;
  std::vector<double> area;
  std::vector<std::array<uint32_t, kRegionCount>> contact;  ///< welded vertices shared with each region
};

Pieces FindPieces(const Mesh& mesh, const WeldedGraph& g, const std::vector<double>& tri_area,
                  const std::vector<uint8_t>& regions) {
  const uint32_t nv = mesh.vertex_count();
  const uint32_t nt = mesh.triangle_count();
  // Incident triangles per representative vertex (CSR).
  std::vector<uint32_t> off(size_t(nv) + 1, 0);
  for (uint32_t i = 0; i < 3 * nt; ++i) ++off[g.rep[mesh.indices[i]] + 1];
  for (uint32_t v = 0; v < nv; ++v) off[v + 1] += off[v];
  std::vector<uint32_t> inc(3 * size_t(nt));
  std::vector<uint32_t> fill(off.begin(), off.end() - 1);
  for (uint32_t i = 0; i < 3 * nt; ++i) inc[fill[g.rep[mesh.indices[i]]]++] = i / 3;

  UnionFind uf(nt);
  for (uint32_t v = 0; v < nv; ++v) {
    std::array<int64_t, kRegionCount> first;
    first.fill(-1);
    for (uint32_t k = off[v]; k < off[v + 1]; ++k) {
      const uint32_t t = inc[k];
      const uint8_t r = regions[t];
      if (first[r] < 0) first[r] = t;
      else uf.Unite(static_cast<uint32_t>(first[r]), t);
    }
  }
  Pieces p;
  p.of_triangle.assign(nt, 0);
  std::vector<int64_t> id(nt, -1);
  for (uint32_t t = 0; t < nt; ++t) {
    const uint32_t root = uf.Find(t);
    if (id[root] < 0) {
      id[root] = static_cast<int64_t>(p.region.size());
      p.region.push_back(regions[t]);
      p.area.push_back(0.0);
      p.contact.push_back({});
    }
    p.of_triangle[t] = static_cast<uint32_t>(id[root]);
    p.area[p.of_triangle[t]] += tri_area[t];
  }
  std::vector<uint32_t> here;
  for (uint32_t v = 0; v < nv; ++v) {
    here.clear();
    for (uint32_t k = off[v]; k < off[v + 1]; ++k) here.push_back(p.of_triangle[inc[k]]);
    std::sort(here.begin(), here.end());
    here.erase(std::unique(here.begin(), here.end()), here.end());
    if (here.size() < 2) continue;
    for (uint32_t a : here)
      for (uint32_t b : here)
        if (p.region[a] != p.region[b]) ++p.contact[a][p.region[b]];
  }
  return p;
}

}  // namespace

void MakeLimbsConnected(const Mesh& mesh, std::vector<uint8_t>& regions, std::string& notes) {
  const WeldedGraph g = BuildWeldedGraph(mesh);
  const std::vector<double> tri_area = TriangleAreas(mesh);
  const uint8_t torso = static_cast<uint8_t>(Region::kTorso);
  size_t moved_limb = 0, moved_torso = 0;
  for (int iter = 0; iter < 6; ++iter) {
    const Pieces p = FindPieces(mesh, g, tri_area, regions);
    std::array<int64_t, kRegionCount> largest;
    largest.fill(-1);
    for (size_t c = 0; c < p.region.size(); ++c) {
      auto& l = largest[p.region[c]];
      if (l < 0 || p.area[c] > p.area[size_t(l)]) l = static_cast<int64_t>(c);
    }
    std::vector<int16_t> target(p.region.size(), -1);
    bool changed = false;
    for (size_t c = 0; c < p.region.size(); ++c) {
      if (static_cast<int64_t>(c) == largest[p.region[c]]) continue;
      if (p.region[c] != torso) {
        // A stray limb piece: to the region it touches most, else the torso.
        int best = torso;
        uint32_t best_contact = 0;
        for (int r = 0; r < kRegionCount; ++r)
          if (p.contact[c][r] > best_contact) best = r, best_contact = p.contact[c][r];
        target[c] = static_cast<int16_t>(best);
      } else {
        // A torso island touching exactly one limb joins that limb.
        int only = -1, touching = 0;
        for (int r = 0; r < kRegionCount; ++r)
          if (p.contact[c][r] > 0) only = r, ++touching;
        if (touching == 1 && only != torso) target[c] = static_cast<int16_t>(only);
      }
    }
    for (uint32_t t = 0; t < regions.size(); ++t) {
      const int16_t to = target[p.of_triangle[t]];
      if (to >= 0 && to != regions[t]) {
        (regions[t] == torso ? moved_torso : moved_limb) += 1;
        regions[t] = static_cast<uint8_t>(to);
        changed = true;
      }
    }
    if (!changed) break;
  }
  if (moved_limb || moved_torso) {
    notes += "connected cleanup: " + std::to_string(moved_limb) + " stray limb triangles reassigned, " +
             std::to_string(moved_torso) + " enclosed torso triangles joined their limb; ";
  }
}

void ComputeVertexRegions(const Mesh& mesh, Segmentation& seg) {
  const uint32_t nv = mesh.vertex_count();
  std::vector<std::array<uint32_t, kRegionCount>> votes(nv, std::array<uint32_t, kRegionCount>{});
  for (uint32_t i = 0; i < mesh.indices.size(); ++i) ++votes[mesh.indices[i]][seg.triangle_regions[i / 3]];
  seg.vertex_regions.assign(nv, kNoRegion);
  for (uint32_t v = 0; v < nv; ++v) {
    uint32_t best = 0;
    for (int r = 0; r < kRegionCount; ++r)
      if (votes[v][r] > best) best = votes[v][r], seg.vertex_regions[v] = static_cast<uint8_t>(r);
  }
}

std::string RegionCounts(const std::vector<uint8_t>& triangle_regions) {
  std::array<size_t, kRegionCount> n{};
  for (uint8_t r : triangle_regions)
    if (r < kRegionCount) ++n[r];
  std::ostringstream s;
  for (int r = 0; r < kRegionCount; ++r) {
    s << (r ? ", " : "") << RegionSymbol(static_cast<Region>(r)) << ' ' << RegionName(static_cast<Region>(r)) << ' '
      << n[r];
  }
  return s.str();
}

}  // namespace segment_detail

using namespace segment_detail;

Result<Segmentation> SegmentByMap(const Mesh& mesh, const std::string& map_path, Context* ctx) {
  Context::Timer timer(ctx, "segment.map");
  if (Status s = CheckMeshForSegmentation(mesh); !s) return s.error();
  std::ifstream in(map_path);
  if (!in) return MakeError(Error::Code::kIo, "segment: cannot read region map '" + map_path + "'");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kConfig, "segment: region map '" + map_path + "' is not valid JSON: " + e.what());
  }
  const bool per_triangle = j.is_object() && j.contains("triangle_regions");
  const bool per_vertex = j.is_object() && j.contains("vertex_regions");
  if (per_triangle == per_vertex) {
    return MakeError(Error::Code::kConfig, "segment: region map '" + map_path +
                                               "' needs exactly one of \"triangle_regions\" or \"vertex_regions\"");
  }
  const nlohmann::json& arr = per_triangle ? j["triangle_regions"] : j["vertex_regions"];
  const size_t want = per_triangle ? mesh.triangle_count() : mesh.vertex_count();
  const char* what = per_triangle ? "triangle_regions" : "vertex_regions";
  if (!arr.is_array() || arr.size() != want) {
    return MakeError(Error::Code::kConfig, std::string("segment: region map '") + map_path + "': \"" + what +
                                               "\" has " + std::to_string(arr.is_array() ? arr.size() : 0) +
                                               " values, the mesh has " + std::to_string(want));
  }
  std::vector<uint8_t> values(want);
  for (size_t i = 0; i < want; ++i) {
    if (!arr[i].is_number_integer() || arr[i].get<int64_t>() < 0 || arr[i].get<int64_t>() >= kRegionCount) {
      return MakeError(Error::Code::kConfig, std::string("segment: region map '") + map_path + "': " + what + "[" +
                                                 std::to_string(i) + "] = " + arr[i].dump() +
                                                 " is not a region 0..4");
    }
    values[i] = static_cast<uint8_t>(arr[i].get<int64_t>());
  }
  Segmentation seg;
  seg.method = "map";
  if (per_triangle) {
    seg.triangle_regions = std::move(values);
  } else {
    seg.triangle_regions.resize(mesh.triangle_count());
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      const uint8_t a = values[mesh.indices[3 * t]], b = values[mesh.indices[3 * t + 1]],
                    c = values[mesh.indices[3 * t + 2]];
      seg.triangle_regions[t] = (b == c) ? b : a;  // majority; all different → the first vertex's
    }
  }
  ComputeVertexRegions(mesh, seg);
  seg.notes = std::string("region map ") + map_path + " (" + what + "); " + RegionCounts(seg.triangle_regions);
  if (ctx) ctx->Info("segment: " + seg.notes);
  return seg;
}

Result<Segmentation> Segment(const Mesh& mesh, SegmentMethod method, Context* ctx) {
  switch (method) {
    case SegmentMethod::kRig: return SegmentByRig(mesh, ctx);
    case SegmentMethod::kGeometry: return SegmentByGeometry(mesh, ctx);
    case SegmentMethod::kAuto: break;
  }
  if (mesh.skin) {
    Result<Segmentation> rig = SegmentByRig(mesh, ctx);
    if (rig.ok()) return rig;
    if (ctx) ctx->Warn("segment: rig not usable (" + rig.error().message + "); falling back to geometry");
  }
  return SegmentByGeometry(mesh, ctx);
}

SegmentationAgreement CompareSegmentations(const Mesh& mesh, const Segmentation& a, const Segmentation& b) {
  SegmentationAgreement out;
  const size_t nt = mesh.triangle_count();
  if (a.triangle_regions.size() != nt || b.triangle_regions.size() != nt || nt == 0) return out;
  const std::vector<double> area = TriangleAreas(mesh);
  double total = 0, same_area = 0;
  size_t same = 0;
  std::array<size_t, kRegionCount> inter{}, uni{};
  for (size_t t = 0; t < nt; ++t) {
    const uint8_t ra = a.triangle_regions[t], rb = b.triangle_regions[t];
    total += area[t];
    if (ra == rb) {
      ++same;
      same_area += area[t];
      if (ra < kRegionCount) ++inter[ra], ++uni[ra];
    } else {
      if (ra < kRegionCount) ++uni[ra];
      if (rb < kRegionCount) ++uni[rb];
    }
  }
  out.triangle_fraction = double(same) / double(nt);
  out.area_fraction = total > 0 ? same_area / total : 0.0;
  for (int r = 0; r < kRegionCount; ++r) out.iou[r] = uni[r] ? double(inter[r]) / double(uni[r]) : 1.0;
  return out;
}

}  // namespace spherechain::baker
