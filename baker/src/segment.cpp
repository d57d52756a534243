// spherechain baker — segmentation dispatch, user region maps, agreement between two segmentations,
// and the helpers the rig and geometry methods share (welded vertex graph, connected limbs).
#include "spherechain/baker/segment.h"

#include <nlohmann/json.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <map>
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
  // Keys from the box's low corner: at most (hi - lo) / cell = 15,625 cells a side (a mesh far from the
  // origin, or of wildly mixed magnitudes, would give x / cell past int64: undefined, found by fuzzing).
  auto key_of = [&](double x, int axis) { return static_cast<int64_t>(std::floor((x - lo[axis]) / cell)); };
  struct Entry {
    std::array<int64_t, 3> key;
    std::array<float, 3> p;
    uint32_t v;
  };
  std::vector<Entry> sorted(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    const float* q = &mesh.positions[3 * size_t(v)];
    sorted[v] = {{key_of(q[0], 0), key_of(q[1], 1), key_of(q[2], 2)}, {q[0], q[1], q[2]}, v};
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
    for (int a = 0; a < 3; ++a) lo_key[a] = key_of(double(e.p[a]) - eps, a), hi_key[a] = key_of(double(e.p[a]) + eps, a);
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
  std::vector<std::array<uint32_t, kMaxRegions>> contact;  ///< welded vertices shared with each region
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
    std::array<int64_t, kMaxRegions> first;
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

void MakeLimbsConnected(const Mesh& mesh, std::vector<uint8_t>& regions, std::string& notes,
                        const RegionLayout& layout, bool keep_loose_parts) {
  const WeldedGraph g = BuildWeldedGraph(mesh);
  const std::vector<double> tri_area = TriangleAreas(mesh);
  const uint8_t torso = static_cast<uint8_t>(layout.trunk());
  const int nreg = layout.count();
  size_t moved_limb = 0, moved_torso = 0;
  for (int iter = 0; iter < 6; ++iter) {
    const Pieces p = FindPieces(mesh, g, tri_area, regions);
    std::array<int64_t, kMaxRegions> largest;
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
        // A loose part (a mesh component touching no other region: a tail's tuft, an eye) may keep the
        // region its bones give it.
        if (keep_loose_parts && std::all_of(p.contact[c].begin(), p.contact[c].end(), [](uint32_t n) { return n == 0; }))
          continue;
        // A stray limb piece: to the region it touches most, else the torso.
        int best = torso;
        uint32_t best_contact = 0;
        for (int r = 0; r < nreg; ++r)
          if (p.contact[c][r] > best_contact) best = r, best_contact = p.contact[c][r];
        target[c] = static_cast<int16_t>(best);
      } else {
        // A torso island touching exactly one limb joins that limb.
        int only = -1, touching = 0;
        for (int r = 0; r < nreg; ++r)
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
  const size_t nreg = size_t(seg.layout.count());
  std::vector<uint32_t> votes(size_t(nv) * nreg, 0);
  for (uint32_t i = 0; i < mesh.indices.size(); ++i)
    if (seg.triangle_regions[i / 3] < nreg) ++votes[size_t(mesh.indices[i]) * nreg + seg.triangle_regions[i / 3]];
  seg.vertex_regions.assign(nv, kNoRegion);
  for (uint32_t v = 0; v < nv; ++v) {
    uint32_t best = 0;
    for (size_t r = 0; r < nreg; ++r)
      if (votes[size_t(v) * nreg + r] > best) best = votes[size_t(v) * nreg + r], seg.vertex_regions[v] = static_cast<uint8_t>(r);
  }
}

std::string RegionCounts(const std::vector<uint8_t>& triangle_regions, const RegionLayout& layout) {
  std::vector<size_t> n(size_t(layout.count()), 0);
  for (uint8_t r : triangle_regions)
    if (r < n.size()) ++n[r];
  std::ostringstream s;
  for (int r = 0; r < layout.count(); ++r) {
    s << (r ? ", " : "") << RegionSymbol(static_cast<Region>(r)) << ' ' << layout.Name(static_cast<Region>(r)) << ' '
      << n[size_t(r)];
  }
  return s.str();
}

std::vector<std::string> NameTokens(std::string_view name) {
  std::vector<std::string> out;
  std::string cur;
  auto flush = [&] {
    if (!cur.empty()) out.push_back(cur), cur.clear();
  };
  for (size_t i = 0; i < name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (!std::isalnum(c)) {
      flush();
      continue;
    }
    if (!cur.empty()) {
      const unsigned char p = static_cast<unsigned char>(name[i - 1]);
      const bool case_up = std::islower(p) && std::isupper(c);
      const bool digit_change = (std::isdigit(p) != 0) != (std::isdigit(c) != 0);
      if (case_up || digit_change) flush();
    }
    cur.push_back(static_cast<char>(std::tolower(c)));
  }
  flush();
  return out;
}

namespace {
bool IsSideToken(const std::string& t) {
  return t == "l" || t == "left" || t == "lft" || t == "r" || t == "right" || t == "rgt";
}
int SideOf(const std::vector<std::string>& tokens) {
  for (const std::string& t : tokens) {
    if (t == "l" || t == "left" || t == "lft") return 1;
    if (t == "r" || t == "right" || t == "rgt") return -1;
  }
  return 0;
}
}  // namespace

void PairMirrorLimbs(RegionLayout& layout) {
  const int limbs = layout.count() - 1;
  std::vector<std::vector<std::string>> tokens(size_t(std::max(limbs, 0)));
  std::vector<std::string> key(tokens.size());
  for (int a = 0; a < limbs; ++a) {
    layout.regions[size_t(a)].mirror = -1;
    tokens[size_t(a)] = NameTokens(layout.regions[size_t(a)].name);
    for (const std::string& t : tokens[size_t(a)])
      if (!IsSideToken(t)) key[size_t(a)] += t + " ";
  }
  for (int a = 0; a < limbs; ++a) {
    const int side = SideOf(tokens[size_t(a)]);
    if (side == 0 || layout.regions[size_t(a)].mirror >= 0) continue;
    for (int b = a + 1; b < limbs; ++b)
      if (layout.regions[size_t(b)].mirror < 0 && SideOf(tokens[size_t(b)]) == -side && key[size_t(a)] == key[size_t(b)]) {
        layout.regions[size_t(a)].mirror = b;
        layout.regions[size_t(b)].mirror = a;
        break;
      }
  }
}

std::array<double, 3> TrunkAxis(const Mesh& mesh, const std::vector<uint8_t>& triangle_regions, Region trunk) {
  const std::vector<double> tri_area = TriangleAreas(mesh);
  double a = 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (uint32_t t = 0; t < mesh.triangle_count() && t < triangle_regions.size(); ++t) {
    if (triangle_regions[t] != uint8_t(trunk)) continue;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = Position(mesh, mesh.indices[3 * t + k]);
      a += tri_area[t];
      c += tri_area[t] * p;
      m += tri_area[t] * p * p.transpose();
    }
  }
  Eigen::Vector3d axis = UpVector(mesh.up_axis);
  if (a > 0.0) {
    c /= a;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m / a - c * c.transpose());
    if (es.eigenvalues()[2] > 0.0) axis = es.eigenvectors().col(2);
    int big = 0;  // a fixed orientation: the largest component positive
    for (int k = 1; k < 3; ++k)
      if (std::abs(axis[k]) > std::abs(axis[big])) big = k;
    if (axis[big] < 0.0) axis = -axis;
  }
  return {axis.x(), axis.y(), axis.z()};
}

}  // namespace segment_detail

using namespace segment_detail;

namespace {

/// A JSON value from a region map, for a message: a number, string (cut at 40 characters), boolean or null as
/// written; an array or object only by its size. Never the whole value: nlohmann's dump() recurses once per
/// level, and a map entry of "[[[[…" 40,000 deep overflowed the stack printing it (found by fuzz_bake_config).
std::string Brief(const nlohmann::json& v) {
  if (v.is_array()) return "an array of " + std::to_string(v.size());
  if (v.is_object()) return "an object of " + std::to_string(v.size()) + " keys";
  const std::string text = v.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return text.size() <= 40 ? text : text.substr(0, 40) + "...";
}

}  // namespace

Result<Segmentation> SegmentByMap(const Mesh& mesh, const std::string& map_path, Context* ctx) {
  Context::Timer timer(ctx, "segment.map");
  if (Status s = CheckMeshForSegmentation(mesh); !s) return s.error();
  std::ifstream in(map_path);
  if (!in) return MakeError(Error::Code::kIo, "segment: cannot read region map '" + map_path + "'");
  if (ctx) ctx->RecordFileRead(map_path);
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kConfig, "segment: region map '" + map_path + "' is not valid JSON: " + e.what());
  }
  if (j.is_object())  // a misspelt key ("Regions") would silently give the paper's five regions
    for (auto it = j.begin(); it != j.end(); ++it)
      if (it.key() != "triangle_regions" && it.key() != "vertex_regions" && it.key() != "regions")
        return MakeError(Error::Code::kConfig, "segment: region map '" + map_path + "': unknown key '" +
                                                   std::string(it.key(), 0, 64) +
                                                   "' (known: triangle_regions, vertex_regions, regions)");
  const bool per_triangle = j.is_object() && j.contains("triangle_regions");
  const bool per_vertex = j.is_object() && j.contains("vertex_regions");
  if (per_triangle == per_vertex) {
    return MakeError(Error::Code::kConfig, "segment: region map '" + map_path +
                                               "' needs exactly one of \"triangle_regions\" or \"vertex_regions\"");
  }
  const nlohmann::json& arr = per_triangle ? j["triangle_regions"] : j["vertex_regions"];
  const size_t want = per_triangle ? mesh.triangle_count() : mesh.vertex_count();
  const char* what = per_triangle ? "triangle_regions" : "vertex_regions";
  const std::string where = std::string("segment: region map '") + map_path + "'";
  if (!arr.is_array() || arr.size() != want) {
    return MakeError(Error::Code::kConfig, where + ": \"" + what + "\" has " +
                                               std::to_string(arr.is_array() ? arr.size() : 0) +
                                               " values, the mesh has " + std::to_string(want));
  }
  // The layout: the paper's five, or the creature regions the map names ("regions": limbs, the trunk last).
  RegionLayout layout;
  if (j.contains("regions")) {
    const nlohmann::json& names = j["regions"];
    if (!names.is_array() || names.size() < 3 || names.size() > size_t(kMaxRegions))
      return MakeError(Error::Code::kConfig, where + ": \"regions\" must be an array of 3 to " +
                                                 std::to_string(kMaxRegions) + " region names (the limbs, the trunk last)");
    layout.paper = false;
    layout.regions.clear();
    for (size_t i = 0; i < names.size(); ++i) {
      if (!names[i].is_string() || names[i].get<std::string>().empty())
        return MakeError(Error::Code::kConfig, where + ": regions[" + std::to_string(i) + "] = " + Brief(names[i]) +
                                                   " is not a region name");
      RegionInfo info;
      info.name = names[i].get<std::string>();
      info.kind = i + 1 == names.size() ? RegionKind::kTrunk : RegionKind::kLimb;
      for (const RegionInfo& other : layout.regions)
        if (other.name == info.name)
          return MakeError(Error::Code::kConfig, where + ": region '" + info.name + "' is named twice in \"regions\"");
      layout.regions.push_back(std::move(info));
    }
    PairMirrorLimbs(layout);
  }
  auto known_names = [&] {
    std::string list;
    for (int r = 0; r < layout.count(); ++r) list += std::string(r ? ", " : "") + layout.Name(Region(r));
    return list + " (or R0..R" + std::to_string(layout.count() - 1) + ", or 0.." + std::to_string(layout.count() - 1) + ")";
  };
  std::vector<uint8_t> values(want);
  for (size_t i = 0; i < want; ++i) {
    const nlohmann::json& e = arr[i];
    int64_t value = -1;
    if (e.is_number_integer()) {
      value = e.get<int64_t>();
    } else if (e.is_string()) {
      const std::string name = e.get<std::string>();
      for (int r = 0; r < layout.count() && value < 0; ++r)
        if (name == layout.Name(Region(r)) || name == RegionSymbol(Region(r))) value = r;
      if (value < 0)
        return MakeError(Error::Code::kConfig, where + ": " + what + "[" + std::to_string(i) + "] = \"" + name +
                                                   "\" names no region of the map; its regions: " + known_names());
    }
    if (value < 0 || value >= layout.count()) {
      return MakeError(Error::Code::kConfig, where + ": " + what + "[" + std::to_string(i) + "] = " + Brief(e) +
                                                 " is not a region 0.." + std::to_string(layout.count() - 1) +
                                                 " or a region name: " + known_names());
    }
    values[i] = static_cast<uint8_t>(value);
  }
  Segmentation seg;
  seg.method = "map";
  seg.layout = std::move(layout);
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
  if (!seg.layout.paper)
    seg.layout.trunk_axis = TrunkAxis(mesh, seg.triangle_regions, seg.layout.trunk());
  ComputeVertexRegions(mesh, seg);
  seg.notes = std::string("region map ") + map_path + " (" + what + "); " + RegionCounts(seg.triangle_regions, seg.layout);
  if (ctx) ctx->Info("segment: " + seg.notes);
  return seg;
}

Result<Segmentation> Segment(const Mesh& mesh, SegmentMethod method, Context* ctx) {
  switch (method) {
    case SegmentMethod::kRig: return SegmentByRig(mesh, ctx);
    case SegmentMethod::kGeometry: return SegmentByGeometry(mesh, ctx);
    case SegmentMethod::kSkeleton: return SegmentBySkeleton(mesh, {}, ctx);
    case SegmentMethod::kAuto: break;
  }
  if (mesh.skin) {
    Result<Segmentation> rig = SegmentByRig(mesh, ctx);
    if (rig.ok()) return rig;
    if (ctx) ctx->Warn("segment: rig not usable (" + rig.error().message + "); falling back to geometry");
  }
  Result<Segmentation> geometry = SegmentByGeometry(mesh, ctx);
  if (geometry.ok() || geometry.error().code != Error::Code::kSegmentation) return geometry;
  // Not a standing body: a rigged creature may still be segmented by its bone tree (the any-skeleton path).
  Result<Segmentation> skeleton = SegmentBySkeleton(mesh, {}, ctx);
  if (skeleton.ok()) {
    if (ctx) ctx->Info("segment: " + geometry.error().message + "; segmented as a creature by its skeleton instead");
    return skeleton;
  }
  return MakeError(Error::Code::kSegmentation, geometry.error().message + "; " + skeleton.error().message);
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
