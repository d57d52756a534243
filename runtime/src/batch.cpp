// BatchJob: refit + detect of many characters sharing one Model, spread through ParallelFor.
#include "spherechain/runtime/batch.h"

#include <cmath>

#include "internal.h"

namespace spherechain::runtime {
namespace {

struct BatchTaskData {
  const BatchJob* job;
};

// One character, serial: the same jobs a caller would run for it alone.
void RunCharacter(const BatchJob& job, CharacterFrame& ch) {
  DetectJob detect;
  detect.model = job.model;
  detect.workspace = ch.workspace;
  detect.method = job.method;
  detect.output = ch.output;
  detect.capacity = ch.capacity;
  detect.count = ch.count;
  detect.stats = ch.stats;
  detect.margin = job.margin;
  detect.fold_margin = job.fold_margin;
  // The detect arguments first: a character that cannot be detected keeps its workspace's spheres untouched.
  Status s = detect.Check();
  if (s != Status::kOk) {
    ch.status = s;
    return;
  }
  if (job.source == RefitSource::kVertices) {
    RefitJob refit;
    refit.positions = ch.positions;
    refit.mode = job.mode;
    refit.model = job.model;
    refit.workspace = ch.workspace;
    s = refit.Run();
  } else {
    JointRefitJob refit;
    refit.model = job.model;
    refit.workspace = ch.workspace;
    refit.joint_matrices = ch.joint_matrices;
    refit.joint_count = job.joint_count;
    s = refit.Run();
  }
  if (s == Status::kOk) s = detect.Run();
  ch.status = s;
}

void BatchTask(void* data, uint32_t begin, uint32_t end) {
  const BatchJob& job = *static_cast<BatchTaskData*>(data)->job;
  const uint64_t b = uint64_t{begin} * job.parallel_grain, e = uint64_t{end} * job.parallel_grain;
  const uint64_t n = job.character_count;
  for (uint64_t i = b; i < e && i < n; ++i) RunCharacter(job, job.characters[i]);
}

}  // namespace

Status BatchJob::Check() const {
  if (!model || (!characters && character_count > 0)) return Status::kErrorNullArgument;
  if (!model->initialized() || parallel_grain == 0 || !std::isfinite(margin) || !std::isfinite(fold_margin) ||
      (fold_margin >= 0.0f && model->fold_margin() < 0.0f) ||
      (source != RefitSource::kVertices && source != RefitSource::kJoints) ||
      (mode != RefitMode::kPaper && mode != RefitMode::kPivotFrame) ||
      (method != DetectMethod::kM1 && method != DetectMethod::kM2))
    return Status::kErrorInvalidJob;
  if (source == RefitSource::kJoints) {
    if (model->joint_count() == 0) return Status::kErrorMissingField;
    if (joint_count != model->joint_count()) return Status::kErrorJointCount;
  }
  return Status::kOk;
}

Status BatchJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  if (parallel_for.run) {
    BatchTaskData data{this};
    // In 64 bits: a grain near 2^32 ("one task") must not wrap the count to 0 tasks.
    const uint64_t tasks = (uint64_t{character_count} + parallel_grain - 1) / parallel_grain;
    parallel_for.run(parallel_for.user, static_cast<uint32_t>(tasks), &BatchTask, &data);
  } else {
    for (uint32_t i = 0; i < character_count; ++i) RunCharacter(*this, characters[i]);
  }
  bool truncated = false;
  for (uint32_t i = 0; i < character_count; ++i) {
    if (Failed(characters[i].status)) return characters[i].status;
    truncated |= IsTruncated(characters[i].status);
  }
  return truncated ? Status::kOkTruncated : Status::kOk;
}

}  // namespace spherechain::runtime
