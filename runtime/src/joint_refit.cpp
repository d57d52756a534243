// JointRefitJob: sphere centres by linear blend skinning of their bind centres, see refit.h.
#include <cstdint>
#include <cstring>

#include "internal.h"

namespace spherechain::runtime {

Status JointRefitJob::Check() const {
  if (!joint_matrices) return Status::kErrorNullArgument;
  if (Status s = Model::Internal::CheckPair(model, workspace); s != Status::kOk) return s;
  if (model->joint_count() == 0) return Status::kErrorMissingField;
  if (joint_count != model->joint_count()) return Status::kErrorJointCount;
  if (reinterpret_cast<uintptr_t>(joint_matrices) % alignof(float) != 0) return Status::kErrorAlignment;
  return Status::kOk;
}

Status JointRefitJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  return Model::Internal::JointRefit(*this);
}

// Every matrix finite before anything is written (kernels::Table::finite: Σ x · 0 is NaN exactly when
// some x is not finite); then the centres by the model's joint records (grouped by influence count: a
// fixed number of blends per group, no branch per sphere; kernels::JointRefitArgs), radii = bind radii.
Status Model::Internal::JointRefit(const JointRefitJob& job) {
  const Model& m = *job.model;
  Workspace& w = *job.workspace;
  const kernels::Table& kernel = kernels::Kernels(static_cast<kernels::Isa>(m.isa_));
  if (!kernel.finite(job.joint_matrices, job.joint_count * kJointMatrixFloats)) return Status::kErrorNonFiniteJoints;
  const kernels::JointRefitArgs args{job.joint_matrices, m.joint_sphere_, m.joint_offsets_, m.joint_weights_,
                                     m.joint_bind_, {m.joint_group_end_[0], m.joint_group_end_[1],
                                                     m.joint_group_end_[2], m.joint_group_end_[3]},
                                     w.x_, w.y_, w.z_};
  kernel.joint_refit(args);
  std::memcpy(w.r_, m.a_.bind_r, sizeof(float) * m.sphere_count_);
  return Status::kOk;
}

}  // namespace spherechain::runtime
