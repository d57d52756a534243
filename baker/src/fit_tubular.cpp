// spherechain baker — the moving circumference for tubular regions (paper §3.1, after Madera et al.
// 2013): the limb's base curve from geodesic level sets of the region, then spheres centred on that
// curve whose radius reaches the nearest surface of the region, neighbours overlapping by PD.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <string>
#include <unordered_map>
#include <utility>

#include "geometry.h"
#include "spherechain/baker/fit.h"

namespace spherechain::baker {

namespace {

using Eigen::Vector3d;
using fit_detail::Vertex;

uint64_t EdgeKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 32) | b;
}

/// The vertices the geodesic distance starts from: the region's boundary where it meets the rest of
/// the mesh (the torso); for a free-standing region, one boundary loop (the one nearest the rest of
/// the mesh, else the largest); for a closed region, the vertex farthest from its centroid.
std::vector<uint32_t> RootVertices(const Mesh& mesh, const std::vector<uint32_t>& tris,
                                   const std::vector<uint8_t>& in_region_tri) {
  std::unordered_map<uint64_t, int> edge_count;
  edge_count.reserve(tris.size() * 3);
  for (uint32_t t : tris)
    for (int k = 0; k < 3; ++k) ++edge_count[EdgeKey(mesh.indices[3 * t + k], mesh.indices[3 * t + (k + 1) % 3])];
  std::unordered_map<uint64_t, bool> boundary;  // boundary edge → shared with a triangle outside
  for (const auto& [key, n] : edge_count)
    if (n == 1) boundary[key] = false;
  Vector3d rest_sum = Vector3d::Zero();
  size_t rest_n = 0;
  const uint32_t tcount = mesh.triangle_count();
  for (uint32_t t = 0; t < tcount; ++t) {
    if (in_region_tri[t]) continue;
    for (int k = 0; k < 3; ++k) {
      auto it = boundary.find(EdgeKey(mesh.indices[3 * t + k], mesh.indices[3 * t + (k + 1) % 3]));
      if (it != boundary.end()) it->second = true;
      rest_sum += Vertex(mesh, mesh.indices[3 * t + k]);
      ++rest_n;
    }
  }
  std::vector<uint32_t> roots;
  for (const auto& [key, shared] : boundary)
    if (shared) {
      roots.push_back(static_cast<uint32_t>(key >> 32));
      roots.push_back(static_cast<uint32_t>(key & 0xffffffffu));
    }
  if (roots.empty() && !boundary.empty()) {
    // Free-standing: group boundary vertices into loops (union–find over boundary edges).
    std::unordered_map<uint32_t, uint32_t> parent;
    auto find = [&](uint32_t v) {
      while (parent[v] != v) v = parent[v] = parent[parent[v]];
      return v;
    };
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    for (const auto& [key, shared] : boundary) edges.emplace_back(key >> 32, key & 0xffffffffu);
    std::sort(edges.begin(), edges.end());
    for (auto [a, b] : edges) {
      parent.try_emplace(a, a);
      parent.try_emplace(b, b);
      const uint32_t ra = find(a), rb = find(b);
      if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
    }
    std::unordered_map<uint32_t, std::vector<uint32_t>> loops;
    std::vector<uint32_t> verts;
    for (const auto& [v, p] : parent) verts.push_back(v);
    std::sort(verts.begin(), verts.end());
    for (uint32_t v : verts) loops[find(v)].push_back(v);
    std::vector<uint32_t> loop_ids;
    for (const auto& [id, vs] : loops) loop_ids.push_back(id);
    std::sort(loop_ids.begin(), loop_ids.end());
    const Vector3d rest_c = rest_n ? Vector3d(rest_sum / static_cast<double>(rest_n)) : Vector3d::Zero();
    double best = std::numeric_limits<double>::infinity();
    for (uint32_t id : loop_ids) {
      const auto& vs = loops[id];
      double score;
      if (rest_n) {
        Vector3d c = Vector3d::Zero();
        for (uint32_t v : vs) c += Vertex(mesh, v);
        score = (c / static_cast<double>(vs.size()) - rest_c).norm();
      } else {
        score = -static_cast<double>(vs.size());
      }
      if (score < best) {
        best = score;
        roots = vs;
      }
    }
  }
  if (roots.empty()) {
    Vector3d c = Vector3d::Zero();
    size_t n = 0;
    for (uint32_t t : tris)
      for (int k = 0; k < 3; ++k, ++n) c += Vertex(mesh, mesh.indices[3 * t + k]);
    c /= static_cast<double>(std::max<size_t>(n, 1));
    double far = -1;
    uint32_t fv = mesh.indices[3 * tris[0]];
    for (uint32_t t : tris)
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.indices[3 * t + k];
        const double d = (Vertex(mesh, v) - c).squaredNorm();
        if (d > far || (d == far && v < fv)) far = d, fv = v;
      }
    roots.push_back(fv);
  }
  std::sort(roots.begin(), roots.end());
  roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
  return roots;
}

}  // namespace

Result<std::vector<FittedSphere>> FitTubular(const Mesh& mesh, const std::vector<uint32_t>& region_triangles,
                                             Region region, const FitParams& params, Context* ctx) {
  const std::string name = RegionName(region);
  if (region_triangles.empty()) return MakeError(Error::Code::kFit, "fit " + name + ": region has no triangles");
  if (!(params.penetration_depth >= 0.0 && params.penetration_depth <= 0.9))
    return MakeError(Error::Code::kFit, "fit: penetration_depth must be in [0, 0.9]");
  const uint32_t tcount = mesh.triangle_count(), vcount = mesh.vertex_count();
  std::vector<uint8_t> in_tri(tcount, 0);
  for (uint32_t t : region_triangles) {
    if (t >= tcount) return MakeError(Error::Code::kFit, "fit " + name + ": triangle index out of range");
    in_tri[t] = 1;
  }

  // Vertex graph of the region (CSR), Euclidean edge lengths.
  std::vector<std::vector<std::pair<uint32_t, double>>> adj(vcount);
  std::vector<uint32_t> region_vertices;
  double edge_sum = 0.0;
  size_t edge_n = 0;
  for (uint32_t t : region_triangles)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.indices[3 * t + k], b = mesh.indices[3 * t + (k + 1) % 3];
      const double len = (Vertex(mesh, a) - Vertex(mesh, b)).norm();
      adj[a].emplace_back(b, len);
      adj[b].emplace_back(a, len);
      edge_sum += len;
      ++edge_n;
      region_vertices.push_back(a);
    }
  std::sort(region_vertices.begin(), region_vertices.end());
  region_vertices.erase(std::unique(region_vertices.begin(), region_vertices.end()), region_vertices.end());
  const double mean_edge = edge_sum / static_cast<double>(edge_n);

  // Geodesic (graph) distance from the root boundary (Dijkstra).
  const std::vector<uint32_t> roots = RootVertices(mesh, region_triangles, in_tri);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> dist(vcount, kInf);
  using QItem = std::pair<double, uint32_t>;
  std::priority_queue<QItem, std::vector<QItem>, std::greater<>> queue;
  for (uint32_t r : roots) {
    dist[r] = 0.0;
    queue.emplace(0.0, r);
  }
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    for (const auto& [w, len] : adj[v])
      if (d + len < dist[w]) {
        dist[w] = d + len;
        queue.emplace(dist[w], w);
      }
  }
  double s_max = 0.0;
  for (uint32_t v : region_vertices)
    if (dist[v] < kInf) s_max = std::max(s_max, dist[v]);
  if (!(s_max > 0.0)) return MakeError(Error::Code::kFit, "fit " + name + ": degenerate region (no length)");

  // Level sets → ring centroids: the base (centre) curve, parameterised by geodesic distance s.
  const double bin = std::max(1.5 * mean_edge, s_max / 400.0);
  const int nbins = std::max(1, static_cast<int>(std::ceil(s_max / bin)));
  std::vector<Vector3d> bin_sum(nbins, Vector3d::Zero());
  std::vector<double> bin_s(nbins, 0.0);
  std::vector<int> bin_n(nbins, 0);
  // Where a level set splits into branches (thumb, fingers, toes) its centroid would fall between
  // them: each level set keeps only its largest connected ring, connectivity taken over the band of
  // this bin and the next.
  auto bin_of = [&](uint32_t v) { return std::min(nbins - 1, static_cast<int>(dist[v] / bin)); };
  std::vector<uint32_t> parent(vcount);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  std::vector<std::vector<uint32_t>> by_bin(nbins);
  for (uint32_t v : region_vertices)
    if (dist[v] < kInf) by_bin[bin_of(v)].push_back(v);
  for (int b = 0; b < nbins; ++b) {
    if (by_bin[b].empty()) continue;
    auto in_band = [&](uint32_t w) { return dist[w] < kInf && (bin_of(w) == b || bin_of(w) == b + 1); };
    std::vector<uint32_t> band = by_bin[b];
    if (b + 1 < nbins) band.insert(band.end(), by_bin[b + 1].begin(), by_bin[b + 1].end());
    for (uint32_t v : band) parent[v] = v;
    for (uint32_t v : band)
      for (const auto& [w, len] : adj[v])
        if (in_band(w)) {
          const uint32_t a = find(v), c = find(w);
          if (a != c) parent[std::max(a, c)] = std::min(a, c);
        }
    std::unordered_map<uint32_t, int> size;
    for (uint32_t v : by_bin[b]) ++size[find(v)];
    uint32_t best_root = 0;
    int best_n = -1;
    for (const auto& [root, n] : size)
      if (n > best_n || (n == best_n && root < best_root)) best_n = n, best_root = root;
    for (uint32_t v : by_bin[b]) {
      if (find(v) != best_root) continue;
      bin_sum[b] += Vertex(mesh, v);
      bin_s[b] += dist[v];
      ++bin_n[b];
    }
  }
  std::vector<double> curve_s;
  std::vector<Vector3d> curve_c;
  for (int b = 0; b < nbins; ++b)
    if (bin_n[b] > 0) {
      curve_s.push_back(bin_s[b] / bin_n[b]);
      curve_c.push_back(bin_sum[b] / bin_n[b]);
    }
  auto centre_at = [&](double s) -> Vector3d {
    if (s <= curve_s.front()) return curve_c.front();
    if (s >= curve_s.back()) return curve_c.back();
    const size_t i = static_cast<size_t>(std::upper_bound(curve_s.begin(), curve_s.end(), s) - curve_s.begin());
    const double u = (s - curve_s[i - 1]) / std::max(curve_s[i] - curve_s[i - 1], 1e-300);
    return (1.0 - u) * curve_c[i - 1] + u * curve_c[i];
  };

  // Candidate positions along the curve: centre on the curve, radius to the nearest region surface.
  const fit_detail::TriangleGrid grid(mesh, region_triangles);
  const double h = bin / 4.0;
  std::vector<double> cand_s;
  std::vector<Vector3d> cand_c;
  std::vector<double> cand_r;
  for (double s = curve_s.front(); s <= curve_s.back() + 1e-12; s += h) {
    // The level-set centroid is off-centre where the limb bends (elbow, knee, wrist): push the centre
    // away from the nearest surface point, inside the cross-section plane (normal: the curve's
    // tangent), while the inscribed radius grows — a few steps towards the section's medial centre.
    Vector3d c = centre_at(s);
    Vector3d tangent = centre_at(s + bin) - centre_at(s - bin);
    tangent = tangent.norm() > 1e-12 ? Vector3d(tangent.normalized()) : Vector3d::Zero();
    Vector3d q;
    double r = grid.NearestDistance(c, &q);
    for (int it = 0; it < 8 && r > 0.0; ++it) {
      Vector3d away = c - q;
      away -= away.dot(tangent) * tangent;
      if (away.norm() < 1e-12) break;
      const Vector3d c2 = c + 0.25 * r * away.normalized();
      Vector3d q2;
      const double r2 = grid.NearestDistance(c2, &q2);
      if (!(r2 > r * (1.0 + 1e-3))) break;
      c = c2, q = q2, r = r2;
    }
    cand_s.push_back(s);
    cand_c.push_back(c);
    cand_r.push_back(r);
  }
  // A sphere "fits" at s when it does not reach past the root boundary or the tip along the curve.
  // Where a level set splits (fingers, toes) its centroid falls between the branches and the radius
  // collapses: such positions are skipped (radius below a quarter of the limb's median radius).
  std::vector<double> sorted_r = cand_r;
  std::nth_element(sorted_r.begin(), sorted_r.begin() + sorted_r.size() / 2, sorted_r.end());
  const double r_floor = 0.25 * sorted_r[sorted_r.size() / 2];
  auto fits = [&](size_t i) {
    return cand_s[i] >= cand_r[i] && s_max - cand_s[i] >= cand_r[i] && cand_r[i] > r_floor;
  };

  const double keep = 1.0 - params.penetration_depth;
  std::vector<size_t> chosen;
  size_t i = 0;
  while (i < cand_s.size() && !fits(i)) ++i;
  if (i == cand_s.size()) {
    // Too short for the fit rule: one sphere at the largest-radius candidate.
    i = static_cast<size_t>(std::max_element(cand_r.begin(), cand_r.end()) - cand_r.begin());
  }
  chosen.push_back(i);
  // The next sphere: among the positions whose sphere overlaps the previous one by at most PD but
  // still touches it (keep·(r_p + r_j) ≤ d ≤ r_p + r_j), the largest — "the best place to construct
  // a sphere" (§3.1). Taking the first admissible position instead lets a dip of the radius (a noisy
  // centre near the elbow or wrist) seed a cluster of tiny spheres. A later position must be 5 %
  // larger to win, so a uniform tube is spaced exactly keep·2r. When no position touches (a gap), the first admissible
  // one is taken.
  for (size_t j = i + 1; j < cand_s.size();) {
    const size_t p = chosen.back();
    size_t best = SIZE_MAX, first = SIZE_MAX;
    for (size_t k = j; k < cand_s.size(); ++k) {
      if (!fits(k)) continue;
      const double d = (cand_c[k] - cand_c[p]).norm();
      if (d < keep * (cand_r[p] + cand_r[k])) continue;
      if (first == SIZE_MAX) first = k;
      if (d > cand_r[p] + cand_r[k]) {
        if (best != SIZE_MAX || cand_s[k] - cand_s[p] > 4.0 * (cand_r[p] + cand_r[k])) break;
        continue;
      }
      if (best == SIZE_MAX || cand_r[k] > 1.05 * cand_r[best]) best = k;  // 5 %: tessellation noise
    }
    const size_t next = best != SIZE_MAX ? best : first;
    if (next == SIZE_MAX) break;
    chosen.push_back(next);
    j = next + 1;
  }
  // The tip: the last position that still fits, unless it is already (nearly) covered.
  for (size_t j = cand_s.size(); j-- > chosen.back() + 1;) {
    if (!fits(j)) continue;
    const size_t p = chosen.back();
    if ((cand_c[j] - cand_c[p]).norm() >= 0.5 * keep * (cand_r[p] + cand_r[j])) chosen.push_back(j);
    break;
  }

  std::vector<FittedSphere> out;
  out.reserve(chosen.size());
  for (size_t k = 0; k < chosen.size(); ++k) {
    FittedSphere s;
    s.center = s.center_phi1 = cand_c[chosen[k]];
    s.radius = s.radius_phi1 = cand_r[chosen[k]];
    s.region = region;
    s.sequence = static_cast<int>(k);
    out.push_back(std::move(s));
  }
  if (ctx)
    ctx->Debug("fit " + name + ": " + std::to_string(out.size()) + " spheres, length " + std::to_string(s_max) +
               ", " + std::to_string(roots.size()) + " root vertices");
  return out;
}

}  // namespace spherechain::baker
