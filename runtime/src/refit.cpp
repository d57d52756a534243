// RefitJob: sphere update from the four pivot polygons (paper §5.1), see refit.h.
#include "internal.h"

namespace spherechain::runtime {
namespace {

struct RefitTaskData {
  const RefitJob* job;
};

void RefitTask(void* data, uint32_t begin, uint32_t end) {
  const RefitJob& job = *static_cast<RefitTaskData*>(data)->job;
  const uint32_t S = job.model->sphere_count();
  const uint64_t b = uint64_t{begin} * job.parallel_grain, e = uint64_t{end} * job.parallel_grain;
  Model::Internal::Refit(job, static_cast<uint32_t>(b < S ? b : S), static_cast<uint32_t>(e < S ? e : S));
}

}  // namespace

// One SoA pass over [begin, end): the SIMD kernel (kernels.inl) evaluates formulas.inl's RefitLanes on
// several spheres per instruction (bit-identical to the scalar formulas).
void Model::Internal::Refit(const RefitJob& job, uint32_t begin, uint32_t end) {
  const Model& m = *job.model;
  Workspace& w = *job.workspace;
  const ModelArrays& a = m.a_;
  const kernels::RefitArgs args{static_cast<const char*>(job.positions.data), job.positions.stride_bytes,
                                job.positions.count - 1,
                                a.pivot_vertices, a.local_x, a.local_y, a.local_z,
                                a.offset_x, a.offset_y, a.offset_z, a.radius_scale,
                                w.x_, w.y_, w.z_, w.r_, job.mode == RefitMode::kPivotFrame};
  if (begin >= end) return;
  kernels::Kernels(static_cast<kernels::Isa>(m.isa_)).refit(args, begin, end);
}

Status RefitJob::Check() const {
  if (!positions.data) return Status::kErrorNullArgument;
  if (Status s = Model::Internal::CheckPair(model, workspace); s != Status::kOk) return s;
  if ((mode != RefitMode::kPaper && mode != RefitMode::kPivotFrame) || parallel_grain == 0)
    return Status::kErrorInvalidJob;
  if (reinterpret_cast<uintptr_t>(positions.data) % alignof(float) != 0) return Status::kErrorAlignment;
  if (positions.stride_bytes < 3 * sizeof(float) || positions.stride_bytes % sizeof(float) != 0)
    return Status::kErrorStride;
  if (positions.count != model->vertex_count()) return Status::kErrorVertexCount;
  return Status::kOk;
}

Status RefitJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  const uint32_t S = model->sphere_count();
  if (parallel_for.run) {
    RefitTaskData data{this};
    // In 64 bits: a grain near 2^32 ("one task") must not wrap the count to 0 tasks.
    const uint64_t tasks = (uint64_t{S} + parallel_grain - 1) / parallel_grain;
    parallel_for.run(parallel_for.user, static_cast<uint32_t>(tasks), &RefitTask, &data);
  } else {
    Model::Internal::Refit(*this, 0, S);
  }
  return Status::kOk;
}

}  // namespace spherechain::runtime
