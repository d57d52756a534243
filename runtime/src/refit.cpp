// RefitJob: sphere update from the four pivot polygons (paper §5.1), see refit.h.
#include <cstring>

#include "internal.h"

namespace spherechain::runtime {
namespace {

struct RefitTaskData {
  const RefitJob* job;
};

void RefitTask(void* data, uint32_t begin, uint32_t end) {
  const RefitJob& job = *static_cast<RefitTaskData*>(data)->job;
  const uint32_t S = job.context->sphere_count();
  const uint64_t b = uint64_t{begin} * job.parallel_grain, e = uint64_t{end} * job.parallel_grain;
  Context::Internal::Refit(job, static_cast<uint32_t>(b < S ? b : S), static_cast<uint32_t>(e < S ? e : S));
}

}  // namespace

void Context::Internal::Refit(const RefitJob& job, uint32_t begin, uint32_t end) {
  Context& c = *job.context;
  const char* base = static_cast<const char*>(job.positions.data);
  const size_t stride = job.positions.stride_bytes;
  const uint32_t* pv = c.pivot_vertices_.data();
  const bool frame_mode = job.mode == RefitMode::kPivotFrame;
  for (uint32_t s = begin; s < end; ++s) {
    float p[4][3];
    const uint32_t* idx = pv + size_t{12} * s;
    for (int k = 0; k < 4; ++k) {
      float v[3][3];
      for (int t = 0; t < 3; ++t) std::memcpy(v[t], base + idx[3 * k + t] * stride, sizeof(float) * 3);
      TriangleCentroid(v[0], v[1], v[2], p[k]);
    }
    float centre[3];
    PivotFrameBasis f;
    if (frame_mode && BuildPivotFrame(p, &f)) {
      const float local[3] = {c.local_x_[s], c.local_y_[s], c.local_z_[s]};
      PivotFrameToModel(f, local, centre);
    } else {
      // Paper §5.1: c += mean displacement of the pivots  ⇔  c = mean(p) + (c_bind − mean(p_bind)).
      for (int k = 0; k < 3; ++k) centre[k] = 0.25f * (p[0][k] + p[1][k] + p[2][k] + p[3][k]);
      centre[0] += c.offset_x_[s];
      centre[1] += c.offset_y_[s];
      centre[2] += c.offset_z_[s];
    }
    c.x_[s] = centre[0];
    c.y_[s] = centre[1];
    c.z_[s] = centre[2];
    c.r_[s] = c.radius_scale_[s] * PivotMeanDistance(p, centre);
  }
}

Status RefitJob::Check() const {
  if (!context || !positions.data) return Status::kErrorNullArgument;
  if (!context->initialized() || (mode != RefitMode::kPaper && mode != RefitMode::kPivotFrame) || parallel_grain == 0)
    return Status::kErrorInvalidJob;
  if (reinterpret_cast<uintptr_t>(positions.data) % alignof(float) != 0) return Status::kErrorAlignment;
  if (positions.stride_bytes < 3 * sizeof(float) || positions.stride_bytes % sizeof(float) != 0)
    return Status::kErrorStride;
  if (positions.count != context->vertex_count()) return Status::kErrorVertexCount;
  return Status::kOk;
}

Status RefitJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  const uint32_t S = context->sphere_count();
  if (parallel_for.run) {
    RefitTaskData data{this};
    parallel_for.run(parallel_for.user, (S + parallel_grain - 1) / parallel_grain, &RefitTask, &data);
  } else {
    Context::Internal::Refit(*this, 0, S);
  }
  return Status::kOk;
}

}  // namespace spherechain::runtime
