// RefitJob: sphere update from the four pivot polygons (paper §5.1), see refit.h.
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

// One SoA pass over [begin, end): the SIMD kernel (kernels.inl) evaluates refit.h's BuildPivotFrame /
// PivotFrameToModel / PivotMeanDistance / TriangleCentroid with the same operations in the same order,
// several spheres per instruction (bit-identical to the scalar formulas).
void Context::Internal::Refit(const RefitJob& job, uint32_t begin, uint32_t end) {
  Context& c = *job.context;
  const kernels::RefitArgs args{static_cast<const char*>(job.positions.data), job.positions.stride_bytes,
                                c.pivot_vertices_.data(), c.local_x_.data(), c.local_y_.data(), c.local_z_.data(),
                                c.offset_x_.data(), c.offset_y_.data(), c.offset_z_.data(), c.radius_scale_.data(),
                                c.x_.data(), c.y_.data(), c.z_.data(), c.r_.data(), job.mode == RefitMode::kPivotFrame};
  if (begin >= end) return;
  if (c.use_avx_)
    kernels::RefitAvx(args, begin, end);
  else
    kernels::RefitSse(args, begin, end);
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
