// spherechain baker — coverage and protrusion of a sphere set against its body mesh (coverage.h):
// a voxel grid, an axis-voted ray-parity inside test with a symbolically perturbed (top-left) fill rule,
// exact sphere membership, CGAL AABB_tree distances for the protruding voxels.
#include "spherechain/baker/coverage.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <utility>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "parallel.h"
#include "surface_tree.h"

namespace spherechain::baker {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point2 = K::Point_2;
using Point3 = K::Point_3;
using surface_detail::Tree;

// Per-voxel state byte: bits 0-1 inside votes (0..3), bits 2-3 known axes (0..3), bit 4 in a sphere.
constexpr uint8_t kInsideVote = 1;
constexpr uint8_t kKnownVote = 4;
constexpr uint8_t kInSphere = 16;

struct Grid {
  std::array<double, 3> origin{};  // corner of voxel (0, 0, 0)
  double h = 0.0;
  std::array<uint32_t, 3> n{};
  std::array<size_t, 3> stride{};  // index = i·stride[0] + j·stride[1] + k·stride[2]
  size_t total = 0;
  // The one formula for a voxel centre: every column and every test uses it, so equal indices give
  // bit-identical coordinates (the fill rule relies on it).
  double Centre(int axis, int64_t i) const { return origin[axis] + (static_cast<double>(i) + 0.5) * h; }
  // Index range [lo, hi] of the centres inside [a, b] along `axis`; lo > hi when none.
  std::pair<int64_t, int64_t> Range(int axis, double a, double b) const {
    const double lo = std::ceil((a - origin[axis]) / h - 0.5);
    const double hi = std::floor((b - origin[axis]) / h - 0.5);
    const double last = static_cast<double>(n[axis]) - 1.0;
    return {static_cast<int64_t>(std::clamp(lo, 0.0, last + 1.0)), static_cast<int64_t>(std::clamp(hi, -1.0, last))};
  }
};

Error Invalid(std::string m) { return MakeError(Error::Code::kInvalidMesh, "coverage: " + std::move(m)); }

// Is column point p inside the counter-clockwise triangle t? Exact orientation; a point on an edge
// belongs to the triangle when the edge direction d has d.y > 0, or d.y == 0 and d.x < 0 — the sign the
// edge test takes at p + ε(−1, −ε) (Simulation of Simplicity), so a line through a shared edge or
// vertex is counted exactly once, as a generic line next to it would be.
bool Covers(const std::array<Point2, 3>& t, const Point2& p) {
  for (int e = 0; e < 3; ++e) {
    const Point2& a = t[e];
    const Point2& b = t[(e + 1) % 3];
    const CGAL::Orientation o = CGAL::orientation(a, b, p);
    if (o == CGAL::LEFT_TURN) continue;
    if (o == CGAL::RIGHT_TURN) return false;
    const bool owned = b.y() > a.y() || (b.y() == a.y() && b.x() < a.x());
    if (!owned) return false;
  }
  return true;
}

double Cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Ray parity along `axis`: adds one known vote (and an inside vote where inside) to every voxel of
// every column with an even number of crossings.
void CastAxis(int axis, const Grid& g, const std::vector<float>& pos, const std::vector<uint32_t>& idx,
              std::vector<uint8_t>& state) {
  const int u = (axis + 1) % 3;
  const int v = (axis + 2) % 3;
  const size_t nu = g.n[u];
  const size_t columns = nu * g.n[v];
  struct Hit {
    uint32_t column;
    double t;
  };
  std::vector<Hit> hits;
  hits.reserve(idx.size() / 3 * 2);
  const size_t tris = idx.size() / 3;
  for (size_t f = 0; f < tris; ++f) {
    std::array<Point2, 3> p;
    std::array<double, 3> along;
    for (int k = 0; k < 3; ++k) {
      const float* x = &pos[3 * size_t{idx[3 * f + k]}];
      p[k] = Point2(x[u], x[v]);
      along[k] = x[axis];
    }
    const CGAL::Orientation o = CGAL::orientation(p[0], p[1], p[2]);
    if (o == CGAL::COLLINEAR) continue;  // seen edge-on: a generic line misses it
    if (o == CGAL::RIGHT_TURN) {
      std::swap(p[1], p[2]);
      std::swap(along[1], along[2]);
    }
    const double umin = std::min({p[0].x(), p[1].x(), p[2].x()}), umax = std::max({p[0].x(), p[1].x(), p[2].x()});
    const double vmin = std::min({p[0].y(), p[1].y(), p[2].y()}), vmax = std::max({p[0].y(), p[1].y(), p[2].y()});
    const auto [iu0, iu1] = g.Range(u, umin, umax);
    const auto [iv0, iv1] = g.Range(v, vmin, vmax);
    if (iu0 > iu1 || iv0 > iv1) continue;
    const double amin = std::min({along[0], along[1], along[2]}), amax = std::max({along[0], along[1], along[2]});
    for (int64_t iv = iv0; iv <= iv1; ++iv) {
      const double cv = g.Centre(v, iv);
      for (int64_t iu = iu0; iu <= iu1; ++iu) {
        const Point2 c(g.Centre(u, iu), cv);
        if (!Covers(p, c)) continue;
        // Crossing parameter by barycentric interpolation (inexact is fine: it only orders voxels).
        const double w0 = Cross(p[1].x() - c.x(), p[1].y() - c.y(), p[2].x() - c.x(), p[2].y() - c.y());
        const double w1 = Cross(p[2].x() - c.x(), p[2].y() - c.y(), p[0].x() - c.x(), p[0].y() - c.y());
        const double w2 = Cross(p[0].x() - c.x(), p[0].y() - c.y(), p[1].x() - c.x(), p[1].y() - c.y());
        const double sum = w0 + w1 + w2;
        double t = sum > 0.0 ? (w0 * along[0] + w1 * along[1] + w2 * along[2]) / sum : along[0];
        t = std::clamp(t, amin, amax);
        hits.push_back({static_cast<uint32_t>(size_t(iv) * nu + size_t(iu)), t});
      }
    }
  }
  // Group by column (counting sort), then order each column's crossings.
  std::vector<uint32_t> start(columns + 1, 0);
  for (const Hit& hit : hits) ++start[hit.column + 1];
  for (size_t c = 0; c < columns; ++c) start[c + 1] += start[c];
  std::vector<double> ts(hits.size());
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (const Hit& hit : hits) ts[fill[hit.column]++] = hit.t;
  }
  hits = {};
  const size_t na = g.n[axis];
  for (size_t iv = 0; iv < g.n[v]; ++iv) {
    for (size_t iu = 0; iu < nu; ++iu) {
      const size_t c = iv * nu + iu;
      const uint32_t b = start[c], e = start[c + 1];
      if ((e - b) % 2 != 0) continue;  // open along this line: unknown for this axis
      std::sort(ts.begin() + b, ts.begin() + e);
      const size_t base = iu * g.stride[u] + iv * g.stride[v];
      uint32_t next = b;  // first crossing not below the current centre
      for (size_t ia = 0; ia < na; ++ia) {
        const double x = g.Centre(axis, static_cast<int64_t>(ia));
        while (next < e && ts[next] < x) ++next;
        uint8_t& s = state[base + ia * g.stride[axis]];
        s = static_cast<uint8_t>(s + kKnownVote + (((next - b) & 1u) ? kInsideVote : 0));
      }
    }
  }
}

// The three axes' votes (CastAxis), cast on all cores into one array each and then added: votes are
// counts, so the sum is the same as casting one axis after another.
void CastAxes(const Grid& g, const std::vector<float>& pos, const std::vector<uint32_t>& idx,
              std::vector<uint8_t>& state) {
  std::array<std::vector<uint8_t>, 3> votes;
  detail::ParallelFor(0, 3, [&](size_t axis) {
    votes[axis].assign(state.size(), 0);
    CastAxis(int(axis), g, pos, idx, votes[axis]);
  });
  for (size_t i = 0; i < state.size(); ++i)
    state[i] = static_cast<uint8_t>(state[i] + votes[0][i] + votes[1][i] + votes[2][i]);
}

// Marks every voxel whose centre is within a sphere.
void MarkSpheres(const Grid& g, const std::vector<Ball>& spheres, std::vector<uint8_t>& state) {
  for (const Ball& s : spheres) {
    const double r = s.radius, r2 = r * r;
    const auto [i0, i1] = g.Range(0, s.center.x() - r, s.center.x() + r);
    const auto [j0, j1] = g.Range(1, s.center.y() - r, s.center.y() + r);
    const auto [k0, k1] = g.Range(2, s.center.z() - r, s.center.z() + r);
    for (int64_t k = k0; k <= k1; ++k) {
      const double dz = g.Centre(2, k) - s.center.z();
      for (int64_t j = j0; j <= j1; ++j) {
        const double dy = g.Centre(1, j) - s.center.y();
        const double rest = r2 - dy * dy - dz * dz;
        if (rest < 0.0) continue;
        const double half = std::sqrt(rest);
        // The analytic row span, widened by a voxel; the exact test decides.
        auto [a, b] = g.Range(0, s.center.x() - half - g.h, s.center.x() + half + g.h);
        a = std::max(a, i0);
        b = std::min(b, i1);
        const size_t row = size_t(j) * g.stride[1] + size_t(k) * g.stride[2];
        for (int64_t i = a; i <= b; ++i) {
          const double dx = g.Centre(0, i) - s.center.x();
          if (dx * dx + dy * dy + dz * dz <= r2) state[row + size_t(i)] |= kInSphere;
        }
      }
    }
  }
}

Status ValidateMesh(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                    const CoverageOptions& options) {
  if (positions.empty()) return Invalid("the mesh has no vertex");
  if (positions.size() % 3 != 0) return Invalid("positions hold " + std::to_string(positions.size()) + " floats, not #V×3");
  if (indices.empty()) return Invalid("the mesh has no triangle");
  if (indices.size() % 3 != 0) return Invalid("indices hold " + std::to_string(indices.size()) + " values, not #T×3");
  if (positions.size() / 3 > std::numeric_limits<uint32_t>::max()) return Invalid("too many vertices");
  const size_t nv = positions.size() / 3;
  for (size_t i = 0; i < positions.size(); ++i)
    if (!std::isfinite(positions[i]))
      return Invalid("vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
  for (size_t i = 0; i < indices.size(); ++i)
    if (indices[i] >= nv)
      return Invalid("triangle " + std::to_string(i / 3) + " has vertex index " + std::to_string(indices[i]) +
                     " out of range (#V = " + std::to_string(nv) + ")");
  if (!(options.voxel_rel > 0.0f) || !std::isfinite(options.voxel_rel))
    return MakeError(Error::Code::kConfig, "coverage: voxel_rel must be > 0 and finite");
  if (options.max_voxels == 0) return MakeError(Error::Code::kConfig, "coverage: max_voxels must be >= 1");
  return Ok{};
}

Status Validate(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                const std::vector<Ball>& spheres, const CoverageOptions& options) {
  if (Status ok = ValidateMesh(positions, indices, options); !ok) return ok;
  if (spheres.empty()) return Invalid("no sphere to measure");
  for (size_t s = 0; s < spheres.size(); ++s) {
    if (!spheres[s].center.allFinite() || !std::isfinite(spheres[s].radius))
      return Invalid("sphere " + std::to_string(s) + " has a non-finite centre or radius");
    if (spheres[s].radius < 0.0) return Invalid("sphere " + std::to_string(s) + " has a negative radius");
  }
  return Ok{};
}

// Bounding box of the vertices and the body height (longest extent).
double MeshBox(const std::vector<float>& positions, std::array<double, 3>* lo, std::array<double, 3>* hi) {
  lo->fill(std::numeric_limits<double>::infinity());
  hi->fill(-std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < positions.size(); i += 3)
    for (int a = 0; a < 3; ++a) {
      (*lo)[a] = std::min((*lo)[a], double(positions[i + a]));
      (*hi)[a] = std::max((*hi)[a], double(positions[i + a]));
    }
  return std::max({(*hi)[0] - (*lo)[0], (*hi)[1] - (*lo)[1], (*hi)[2] - (*lo)[2]});
}

// Cube voxels over [lo, hi]; n = ceil(extent / h) with a 1/1000-voxel slack so an extent of exactly N
// voxels (up to the float rounding of voxel_rel) is N voxels, not N + 1. Enlarged until the grid fits
// max_voxels.
Grid MakeGrid(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double height,
              const CoverageOptions& options) {
  Grid g;
  g.h = double(options.voxel_rel) * height;
  for (;;) {
    std::array<double, 3> n;
    for (int a = 0; a < 3; ++a) n[a] = std::max(1.0, std::ceil((hi[a] - lo[a]) / g.h - 1e-3));
    const double total = n[0] * n[1] * n[2];
    if (total <= double(options.max_voxels)) {
      for (int a = 0; a < 3; ++a) g.n[a] = static_cast<uint32_t>(n[a]);
      break;
    }
    g.h *= std::cbrt(total / double(options.max_voxels)) * (1.0 + 1e-9);
  }
  for (int a = 0; a < 3; ++a) g.origin[a] = 0.5 * (lo[a] + hi[a]) - (double(g.n[a]) * g.h) / 2.0;
  g.stride = {1, size_t{g.n[0]}, size_t{g.n[0]} * g.n[1]};
  g.total = size_t{g.n[0]} * g.n[1] * g.n[2];
  return g;
}

// How far the skin lies outside the spheres: per vertex used by a non-degenerate triangle, max(0, the least
// ‖v − c‖ − r over the spheres), weighted by a third of the area of each triangle using it; the weighted
// median, 95th percentile (the smallest distance with at least that share of the area at or below it) and
// maximum, relative to the body height, and the area share within kSkinWithinRel of the height.
void SkinOutside(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                 const std::vector<Ball>& spheres, double height, CoverageStats* st) {
  const size_t V = positions.size() / 3;
  std::vector<double> area(V, 0.0);
  for (size_t f = 0; f + 2 < indices.size(); f += 3) {
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k)
      p[k] = Eigen::Vector3d(positions[3 * size_t{indices[f + k]}], positions[3 * size_t{indices[f + k]} + 1],
                             positions[3 * size_t{indices[f + k]} + 2]);
    const double a = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    for (int k = 0; k < 3; ++k) area[indices[f + k]] += a / 3.0;
  }
  std::vector<std::pair<double, double>> skin;  // (distance / height, area)
  double total = 0.0;
  for (size_t v = 0; v < V; ++v) {
    if (!(area[v] > 0.0)) continue;
    const Eigen::Vector3d x(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    double d = std::numeric_limits<double>::infinity();
    for (const Ball& b : spheres) d = std::min(d, (x - b.center).norm() - b.radius);
    skin.emplace_back(std::max(0.0, d) / height, area[v]);
    total += area[v];
  }
  if (skin.empty() || !(total > 0.0)) return;
  std::sort(skin.begin(), skin.end());
  auto quantile = [&](double q) {
    double acc = 0.0;
    for (const auto& [d, a] : skin)
      if ((acc += a) >= q * total) return d;
    return skin.back().first;
  };
  st->skin_outside_p50_rel = quantile(0.5);
  st->skin_outside_p95_rel = quantile(0.95);
  st->skin_outside_max_rel = skin.back().first;
  double within = 0.0;
  for (const auto& [d, a] : skin) within += d <= kSkinWithinRel ? a : 0.0;
  st->skin_within_share = within / total;
}

Result<CoverageStats> Measure(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                              const std::vector<Ball>& spheres, const CoverageOptions& options) {
  // Bounding boxes: the mesh's (height), then with the spheres (grid).
  std::array<double, 3> mlo, mhi;
  const double height = MeshBox(positions, &mlo, &mhi);
  if (!(height > 0.0)) return Invalid("the mesh has zero extent (all vertices coincide)");
  std::array<double, 3> lo = mlo, hi = mhi;
  for (const Ball& s : spheres)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], s.center[a] - s.radius);
      hi[a] = std::max(hi[a], s.center[a] + s.radius);
    }

  const Grid g = MakeGrid(lo, hi, height, options);
  std::vector<uint8_t> state(g.total, 0);
  CastAxes(g, positions, indices, state);
  MarkSpheres(g, spheres, state);

  CoverageStats st;
  st.voxel_size = g.h;
  st.body_height = height;
  for (int a = 0; a < 3; ++a) st.grid_dims[a] = g.n[a];
  if (options.per_sphere) st.sphere_outside_max_rel.assign(spheres.size(), 0.0f);
  std::vector<uint32_t> outside;  // union voxels outside the body
  for (size_t i = 0; i < g.total; ++i) {
    const uint8_t s = state[i];
    const int in = s & 3, known = (s >> 2) & 3;
    const bool inside = 2 * in > known;
    if (2 * in == known) ++st.voxels_undecided;  // tie, or no known axis
    const bool sphere = (s & kInSphere) != 0;
    st.voxels_inside_body += inside;
    st.voxels_in_spheres += sphere;
    st.voxels_both += inside && sphere;
    if (sphere && !inside) outside.push_back(static_cast<uint32_t>(i));
  }
  const double vol = g.h * g.h * g.h;
  st.body_volume = st.voxels_inside_body * vol;
  st.spheres_volume = st.voxels_in_spheres * vol;
  st.coverage = st.voxels_inside_body ? double(st.voxels_both) / st.voxels_inside_body : 0.0;
  st.protrusion =
      st.voxels_in_spheres ? double(st.voxels_in_spheres - st.voxels_both) / st.voxels_in_spheres : 0.0;

  if (!outside.empty()) {
    const surface_detail::TriangleList tris = surface_detail::NonDegenerateTriangles(positions, indices).triangles;
    if (tris.empty()) return Invalid("every triangle is degenerate (zero area)");
    Tree tree(tris.begin(), tris.end());
    tree.accelerate_distance_queries();
    std::vector<float> dist(outside.size());
    auto centre = [&](size_t i) {
      const size_t ix = i % g.n[0], iy = (i / g.n[0]) % g.n[1], iz = i / g.stride[2];
      return Point3(g.Centre(0, int64_t(ix)), g.Centre(1, int64_t(iy)), g.Centre(2, int64_t(iz)));
    };
    // Fixed chunks on all cores; in a chunk a row neighbour's closest point bounds the search well,
    // otherwise the tree's own kd-tree hint (the distance is exact either way).
    constexpr size_t kChunk = 1024;
    (void)tree.closest_point(centre(outside[0]));  // builds the search structures: not in parallel
    detail::ParallelFor(0, (outside.size() + kChunk - 1) / kChunk, [&](size_t chunk) {
      Point3 hint;
      for (size_t q = chunk * kChunk; q < std::min(outside.size(), (chunk + 1) * kChunk); ++q) {
        const Point3 c = centre(outside[q]);
        hint = (q > chunk * kChunk && outside[q - 1] + 1 == outside[q]) ? tree.closest_point(c, hint)
                                                                        : tree.closest_point(c);
        dist[q] = static_cast<float>(std::sqrt(CGAL::squared_distance(c, hint)) / height);
      }
    });
    if (options.per_sphere)
      for (size_t q = 0; q < outside.size(); ++q) {
        const Point3 c = centre(outside[q]);
        for (size_t s = 0; s < spheres.size(); ++s) {
          const Eigen::Vector3d d = Eigen::Vector3d(c.x(), c.y(), c.z()) - spheres[s].center;
          if (d.squaredNorm() <= spheres[s].radius * spheres[s].radius)
            st.sphere_outside_max_rel[s] = std::max(st.sphere_outside_max_rel[s], dist[q]);
        }
      }
    const size_t k95 = static_cast<size_t>(std::floor(0.95 * double(dist.size() - 1)));
    std::nth_element(dist.begin(), dist.begin() + k95, dist.end());
    st.outside_p95_rel = dist[k95];
    st.outside_max_rel = *std::max_element(dist.begin() + k95, dist.end());
  }
  SkinOutside(positions, indices, spheres, height, &st);
  return st;
}

}  // namespace

Result<CoverageStats> MeasureCoverage(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                                      const std::vector<Ball>& spheres, const CoverageOptions& options,
                                      Context* ctx) {
  Context::Timer timer(ctx, "coverage");
  if (Status ok = Validate(positions, indices, spheres, options); !ok) return ok.error();
  try {
    return Measure(positions, indices, spheres, options);
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kInternal, std::string("coverage: CGAL: ") + e.what());
  }
}

Result<InteriorVoxels> VoxelizeInterior(const std::vector<float>& positions, const std::vector<uint32_t>& indices,
                                        const CoverageOptions& options, Context* ctx) {
  Context::Timer timer(ctx, "voxelize");
  if (Status ok = ValidateMesh(positions, indices, options); !ok) return ok.error();
  try {
    std::array<double, 3> lo, hi;
    const double height = MeshBox(positions, &lo, &hi);
    if (!(height > 0.0)) return Invalid("the mesh has zero extent (all vertices coincide)");
    const Grid g = MakeGrid(lo, hi, height, options);
    std::vector<uint8_t> state(g.total, 0);
    CastAxes(g, positions, indices, state);
    InteriorVoxels out;
    out.origin = Eigen::Vector3d(g.origin[0], g.origin[1], g.origin[2]);
    out.voxel_size = g.h;
    for (int a = 0; a < 3; ++a) out.dims[a] = g.n[a];
    out.body_height = height;
    for (size_t i = 0; i < g.total; ++i) {
      const int in = state[i] & 3, known = (state[i] >> 2) & 3;
      if (2 * in > known) out.inside.push_back(static_cast<uint32_t>(i));
      if (2 * in == known) ++out.undecided;
    }
    return out;
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kInternal, std::string("coverage: CGAL: ") + e.what());
  }
}

}  // namespace spherechain::baker
