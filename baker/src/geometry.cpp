// spherechain baker — internal geometry helpers for the fitting stage (see geometry.h).
#include "geometry.h"

#include <algorithm>
#include <cmath>

namespace spherechain::baker::fit_detail {

using Eigen::Vector3d;

Vector3d UpVector(UpAxis axis) {
  switch (axis) {
    case UpAxis::kZ: return Vector3d::UnitZ();
    case UpAxis::kX: return Vector3d::UnitX();
    case UpAxis::kY: break;
  }
  return Vector3d::UnitY();
}

Vector3d ClosestPointOnTriangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // degenerate triangle
  const double v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

double RayTriangle(const Vector3d& o, const Vector3d& d, const Vector3d& a, const Vector3d& b, const Vector3d& c,
                   double t_min) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Vector3d e1 = b - a, e2 = c - a;
  const Vector3d pv = d.cross(e2);
  const double det = e1.dot(pv);
  const double scale = e1.squaredNorm() * e2.squaredNorm() * d.squaredNorm();
  if (det * det <= 1e-24 * scale) return kInf;  // ray parallel to the triangle (or degenerate)
  const double inv = 1.0 / det;
  const Vector3d tv = o - a;
  const double u = tv.dot(pv) * inv;
  if (u < 0.0 || u > 1.0) return kInf;
  const Vector3d qv = tv.cross(e1);
  const double v = d.dot(qv) * inv;
  if (v < 0.0 || u + v > 1.0) return kInf;
  const double t = e2.dot(qv) * inv;
  return t > t_min ? t : kInf;
}

TriangleGrid::TriangleGrid(const Mesh& mesh, const std::vector<uint32_t>& triangles) {
  const size_t n = triangles.size();
  a_.reserve(n);
  b_.reserve(n);
  c_.reserve(n);
  Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double edge_sum = 0.0;
  for (uint32_t t : triangles) {
    const uint32_t* ix = &mesh.indices[3 * static_cast<size_t>(t)];
    a_.push_back(Vertex(mesh, ix[0]));
    b_.push_back(Vertex(mesh, ix[1]));
    c_.push_back(Vertex(mesh, ix[2]));
    for (const Vector3d* q : {&a_.back(), &b_.back(), &c_.back()}) {
      lo = lo.cwiseMin(*q);
      hi = hi.cwiseMax(*q);
    }
    edge_sum += (b_.back() - a_.back()).norm() + (c_.back() - b_.back()).norm() + (a_.back() - c_.back()).norm();
  }
  stamp_.assign(n, 0);
  if (n == 0) {
    cell_start_.assign(2, 0);
    return;
  }
  lo_ = lo;
  const Vector3d ext = (hi - lo).cwiseMax(1e-12);
  // Cell edge: ~2 mean edges, but no more than ~64^3 cells over the box.
  double cell = std::max(2.0 * edge_sum / (3.0 * static_cast<double>(n)), 1e-12);
  cell = std::max(cell, std::cbrt(ext.prod() / 262144.0));
  cell_ = cell;
  for (int k = 0; k < 3; ++k) dims_[k] = std::clamp(static_cast<int>(ext[k] / cell) + 1, 1, 512);
  const size_t cells = static_cast<size_t>(dims_[0]) * dims_[1] * dims_[2];
  auto cell_range = [&](size_t i, int* l, int* h) {
    const Vector3d tlo = a_[i].cwiseMin(b_[i]).cwiseMin(c_[i]), thi = a_[i].cwiseMax(b_[i]).cwiseMax(c_[i]);
    for (int k = 0; k < 3; ++k) {
      l[k] = std::clamp(static_cast<int>((tlo[k] - lo_[k]) / cell_), 0, dims_[k] - 1);
      h[k] = std::clamp(static_cast<int>((thi[k] - lo_[k]) / cell_), 0, dims_[k] - 1);
    }
  };
  std::vector<uint32_t> count(cells + 1, 0);
  int l[3], h[3];
  for (size_t i = 0; i < n; ++i) {
    cell_range(i, l, h);
    for (int z = l[2]; z <= h[2]; ++z)
      for (int y = l[1]; y <= h[1]; ++y)
        for (int x = l[0]; x <= h[0]; ++x) ++count[CellIndex(x, y, z) + 1];
  }
  for (size_t i = 0; i < cells; ++i) count[i + 1] += count[i];
  cell_start_ = count;
  cell_items_.resize(count[cells]);
  for (size_t i = 0; i < n; ++i) {
    cell_range(i, l, h);
    for (int z = l[2]; z <= h[2]; ++z)
      for (int y = l[1]; y <= h[1]; ++y)
        for (int x = l[0]; x <= h[0]; ++x) cell_items_[count[CellIndex(x, y, z)]++] = static_cast<uint32_t>(i);
  }
}

double TriangleGrid::NearestDistance(const Vector3d& p, Vector3d* closest) const {
  double best2 = std::numeric_limits<double>::infinity();
  if (a_.empty()) return best2;
  if (++epoch_ == 0) {
    std::fill(stamp_.begin(), stamp_.end(), 0);
    epoch_ = 1;
  }
  int pc[3];
  for (int k = 0; k < 3; ++k) pc[k] = std::clamp(static_cast<int>(std::floor((p[k] - lo_[k]) / cell_)), 0, dims_[k] - 1);
  const int max_ring = std::max({dims_[0], dims_[1], dims_[2]});
  for (int ring = 0; ring <= max_ring; ++ring) {
    for (int z = pc[2] - ring; z <= pc[2] + ring; ++z) {
      if (z < 0 || z >= dims_[2]) continue;
      for (int y = pc[1] - ring; y <= pc[1] + ring; ++y) {
        if (y < 0 || y >= dims_[1]) continue;
        const bool yz_face = std::abs(z - pc[2]) == ring || std::abs(y - pc[1]) == ring;
        for (int x = pc[0] - ring; x <= pc[0] + ring; x += (yz_face || ring == 0) ? 1 : 2 * ring) {
          if (x < 0 || x >= dims_[0]) continue;
          const int cidx = CellIndex(x, y, z);
          for (uint32_t s = cell_start_[cidx]; s < cell_start_[cidx + 1]; ++s) {
            const uint32_t t = cell_items_[s];
            if (stamp_[t] == epoch_) continue;
            stamp_[t] = epoch_;
            const Vector3d q = ClosestPointOnTriangle(p, a_[t], b_[t], c_[t]);
            const double d2 = (q - p).squaredNorm();
            if (d2 < best2) {
              best2 = d2;
              if (closest) *closest = q;
            }
          }
        }
      }
    }
    const double reach = ring * cell_;  // every cell of ring + 1 lies at least this far from p
    if (best2 <= reach * reach) break;
  }
  return std::sqrt(best2);
}

}  // namespace spherechain::baker::fit_detail

#include "spherechain/baker/fit.h"

namespace spherechain::baker::fit_detail {

double BodyHeight(const Mesh& mesh, const Eigen::Vector3d& up) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (uint32_t v : mesh.indices) {
    const double h = Vertex(mesh, v).dot(up);
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  return hi >= lo ? hi - lo : 0.0;
}

double DiskStep(const Mesh& mesh, const FitParams& params) {
  if (params.disk_step > 0.0) return params.disk_step;
  return params.disk_step_rel * BodyHeight(mesh, UpVector(mesh.up_axis));
}

}  // namespace spherechain::baker::fit_detail
