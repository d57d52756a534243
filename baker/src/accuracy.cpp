// spherechain baker — the accuracy measure F of §3.2: F_i = ⊙.r − ‖⊙.c − v_i‖.
#include <algorithm>
#include <cmath>

#include "spherechain/baker/fit.h"

namespace spherechain::baker {

void AccuracyAccumulator::Add(const Eigen::Vector3d& c, double r, const Eigen::Vector3d& v) {
  const double f = r - (c - v).norm();
  if (n_ == 0) {
    min_ = max_ = f;
  } else {
    min_ = std::min(min_, f);
    max_ = std::max(max_, f);
  }
  sum_abs_ += std::abs(f);
  sum_sq_ += f * f;
  ++n_;
}

AccuracyStats AccuracyAccumulator::Stats() const {
  AccuracyStats s;
  s.count = n_;
  if (n_ == 0) return s;
  const double n = static_cast<double>(n_);
  s.mean_abs_f = sum_abs_ / n;
  s.rms_f = std::sqrt(sum_sq_ / n);
  s.min_f = min_;
  s.max_f = max_;
  return s;
}

}  // namespace spherechain::baker
