// Session: animate → refit → detect → narrow phase, frame by frame (session.h).
#include "spherechain/playback/session.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "spherechain/runtime/runtime.h"

namespace spherechain::playback {

namespace {

using Clock = std::chrono::steady_clock;

Error ConfigError(std::string message) { return MakeError(Error::Code::kConfig, std::move(message)); }

/// The skinning matrices of `scratch` (column-major 4×4, what the last skinning used) in the runtime's
/// joint layout (#J × 12, row-major 3×4).
void JointMatrices(const SkinningScratch& scratch, std::vector<float>* out) {
  out->resize(scratch.matrices.size() * runtime::kJointMatrixFloats);
  for (size_t j = 0; j < scratch.matrices.size(); ++j)
    runtime::JointMatrixFromColumnMajor(scratch.matrices[j].data(), out->data() + j * runtime::kJointMatrixFloats);
}

/// Runs `f` `repeat` times (>= 1): the minimum wall time into *us, the last run's status (the first failure
/// stops the runs and is returned, *us untouched).
template <class F>
runtime::Status Time(uint32_t repeat, F&& f, double* us) {
  double best = 1e300;
  runtime::Status s = runtime::Status::kOk;
  for (uint32_t r = 0; r < repeat; ++r) {
    const auto t0 = Clock::now();
    s = f();
    const double t = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    if (runtime::Failed(s)) return s;
    best = std::min(best, t);
  }
  *us = best;
  return s;
}

}  // namespace

const char* ToString(PlayRefit r) {
  switch (r) {
    case PlayRefit::kPaper: return "paper";
    case PlayRefit::kPivotFrame: return "frame";
    case PlayRefit::kJoints: return "joints";
  }
  return "?";
}

Status Session::RuntimeFailure(const char* job, runtime::Status s) {
  runtime_status_ = s;
  // A bind pose passing through itself beyond the narrow phase's budget is the asset's fault, not ours.
  if (s == runtime::Status::kErrorBindPoseTangled)
    return MakeError(Error::Code::kFormat, std::string(job) + ": " + runtime::ToString(s) +
                                               " (re-bake it from a mesh that does not pass through itself)");
  if (s == runtime::Status::kErrorCreaseTooWide)  // the asset's crease against its mesh: a bake's choice
    return MakeError(Error::Code::kFormat, std::string(job) + ": " + runtime::ToString(s) +
                                               " (re-bake it with a smaller crease_rel, or from a mesh whose bind pose "
                                               "is not collapsed)");
  if (s == runtime::Status::kErrorFrameTangled)  // the frame's positions: the animation or its skinning
    return MakeError(Error::Code::kFormat, std::string(job) + " (frame '" + frame_.label + "'): " + runtime::ToString(s));
  return MakeError(Error::Code::kInternal, std::string(job) + ": " + runtime::ToString(s));
}

Status Session::Init(const runtime::AssetView& view, const Mesh& mesh, const SessionOptions& o) {
  *this = Session();
  if (!view.valid()) return ConfigError("the asset is not loaded");
  if (mesh.vertex_count() != view.vertex_count)
    return ConfigError("the mesh has " + std::to_string(mesh.vertex_count()) + " vertices, the asset was baked from " +
                       std::to_string(view.vertex_count));
  const bool joints = o.spheres && o.refit == PlayRefit::kJoints;
  if (joints && !view.asset->sphere_joints())
    return ConfigError("the asset has no joint weights (schema v" + std::to_string(view.asset->schema_version()) +
                       ", or baked from a mesh without a skin): refit from joints needs an asset baked from a rigged "
                       "character");
  if (joints && (!mesh.skin || view.asset->joint_count() != mesh.skin->joints.size()))
    return ConfigError("the asset was baked for " + std::to_string(view.asset->joint_count()) + " joints, the mesh has " +
                       std::to_string(mesh.skin ? mesh.skin->joints.size() : 0));
  if (!o.spheres && o.narrow != SessionNarrow::kEvery)
    return ConfigError("a session without spheres runs the narrow phase over every pair (SessionNarrow::kEvery)");
  if (o.narrow == SessionNarrow::kBehindM2 && !(std::isfinite(o.narrow_behind_margin) && o.narrow_behind_margin > 0.0f))
    return ConfigError("narrow_behind_margin " + std::to_string(o.narrow_behind_margin) +
                       ": expected a finite multiple of the contact margin > 0");
  if (o.narrow == SessionNarrow::kBehindM2 && !(std::isfinite(o.fold_closing) && o.fold_closing >= 0.0f))
    return ConfigError("fold_closing " + std::to_string(o.fold_closing) +
                       ": expected a finite multiple of the contact margin >= 0");
  if (o.narrow != SessionNarrow::kNone && o.contact_capacity == 0) return ConfigError("contact_capacity must be > 0");
  options_ = o;
  mesh_ = &mesh;
  repeat_ = std::max(1u, o.repeat);

  // One Model and one Workspace: the refit and broad phase, and the narrow phase in the same blocks.
  const bool behind = o.narrow == SessionNarrow::kBehindM2;
  runtime::ModelOptions model_options;
  model_options.narrow_phase = o.narrow != SessionNarrow::kNone;
  model_options.narrow_phase_regions =
      behind ? runtime::NarrowPhaseRegions::kReach : runtime::NarrowPhaseRegions::kSurrounding;
  if (o.spheres || model_options.narrow_phase) {
    if (runtime::Status s = model_.Init(view, model_options); runtime::Failed(s)) {
      if (s != runtime::Status::kErrorMissingField) return RuntimeFailure("runtime Model::Init", s);
      runtime_status_ = s;  // only the narrow phase needs fields an asset may lack
      return MakeError(Error::Code::kFormat, std::string("narrow phase: ") + runtime::ToString(s) +
                                                 " (baked before the narrow phase existed: re-bake it)");
    }
    if (runtime::Status s = workspace_.Init(model_); runtime::Failed(s))
      return RuntimeFailure("runtime Workspace::Init", s);
  }
  if (o.spheres) {
    if (o.m1) out_m1_.resize(runtime::DetectBound(view, runtime::DetectMethod::kM1));
    if (o.m2) out_m2_.resize(runtime::DetectBound(view, runtime::DetectMethod::kM2));
  }
  if (o.narrow != SessionNarrow::kNone) {
    if (behind)  // M2's pairs, then (the crease rule) the folds: BehindPairs
      out_behind_.resize(size_t{runtime::DetectBound(view, runtime::DetectMethod::kM2)} + narrow_model().fold_pair_count());
    if (o.crease && narrow_model().has_crease())
      exclusions_ = runtime::Exclusions::kCrease;
    contacts_.resize(o.contact_capacity);
    if (exclusions_ == runtime::Exclusions::kCrease) depths_.resize(o.contact_capacity);
  }
  if (o.reach_model) {
    runtime::Status s = reach_.Init(view, runtime::NarrowPhaseRegions::kReach);
    if (runtime::Succeeded(s)) s = reach_ws_.Init(reach_);
    if (runtime::Failed(s)) return RuntimeFailure("narrow phase (reach regions)", s);
  }
  view_ = view;
  return Ok{};
}

const runtime::NarrowPhaseModel& Session::narrow_model() const {
  static const runtime::NarrowPhaseModel kNoNarrowPhase;
  return model_.narrow_phase() ? *model_.narrow_phase() : kNoNarrowPhase;
}

runtime::NarrowPhaseWorkspace& Session::narrow_workspace() {
  static runtime::NarrowPhaseWorkspace no_narrow_phase;  // uninitialised: every job refuses it, writes nothing
  return workspace_.narrow_phase() ? *workspace_.narrow_phase() : no_narrow_phase;
}

Status Session::Step(const Animation& animation, uint32_t f) {
  std::string label;
  if (auto s = animation.Frame(*mesh_, f, &scratch_, &positions_, &label); !s.ok()) return s;
  // The frame's joint matrices, in the runtime's layout: for the joint refit and for a consumer that asked.
  const bool joints = options_.spheres && options_.refit == PlayRefit::kJoints;
  // The narrow phase's joint-matrix cull (an asset baked with skin weights) takes them too.
  const bool cull = options_.narrow == SessionNarrow::kEvery && exclusions_ == runtime::Exclusions::kCrease &&
                    model_.narrow_phase() && model_.narrow_phase()->has_joint_cull();
  const bool give = (options_.joint_matrices || cull) && view_.asset->sphere_joints() &&
                    view_.asset->joint_count() == scratch_.matrices.size();
  if (joints || give) JointMatrices(scratch_, &joint_matrices_);
  return Run(positions_.data(), joints || give ? joint_matrices_.data() : nullptr, f, std::move(label));
}

Status Session::StepBind() {
  // The joint refit at the bind pose takes the rest pose's skinning matrices.
  const bool joints = options_.spheres && options_.refit == PlayRefit::kJoints;
  if (joints) {
    RestLocals(*mesh_->skin, &scratch_.locals);
    if (auto s = GlobalMatrices(*mesh_->skin, scratch_.locals, &scratch_.globals); !s.ok()) return s;
    if (auto s = SkinningMatrices(*mesh_->skin, scratch_.globals, &scratch_.matrices); !s.ok()) return s;
    JointMatrices(scratch_, &joint_matrices_);
  }
  return Run(mesh_->positions.data(), joints ? joint_matrices_.data() : nullptr, SessionFrame::kBind, "bind");
}

Status Session::Run(const float* positions, const float* joint_matrices, uint32_t frame, std::string label) {
  if (!initialized()) return ConfigError("the session is not initialised");
  frame_ = SessionFrame{};
  frame_.frame = frame;
  frame_.label = std::move(label);
  frame_.positions = {positions, size_t{view_.vertex_count} * 3};
  if (joint_matrices)
    frame_.joint_matrices = {joint_matrices, size_t{view_.asset->joint_count()} * runtime::kJointMatrixFloats};
  frame_.exclusions = exclusions_;
  if (options_.spheres) {
    if (auto s = Refit(positions, joint_matrices); !s.ok()) return s;
    if (auto s = Detect(); !s.ok()) return s;
  }
  if (options_.narrow != SessionNarrow::kNone) return Narrow(positions, joint_matrices);
  return Ok{};
}

Status Session::Play(const Animation& animation, const std::function<Status(const SessionFrame&)>& consume) {
  for (uint32_t f = 0; f < animation.frames; ++f) {
    if (auto s = Step(animation, f); !s.ok()) return s;
    if (auto s = consume(frame_); !s.ok()) return s;
  }
  return Ok{};
}

Status Session::Refit(const float* positions, const float* joint_matrices) {
  runtime::RefitJob refit;
  refit.model = &model_;
  refit.workspace = &workspace_;
  refit.mode = options_.refit == PlayRefit::kPaper ? runtime::RefitMode::kPaper : runtime::RefitMode::kPivotFrame;
  refit.positions = {positions, view_.vertex_count, 12};
  if (options_.refit == PlayRefit::kJoints) {
    if (!joint_matrices) return ConfigError("refit from joints: the frame has no joint matrices");
    if (options_.joint_reference) {  // the vertex refit (pivot frame) of the same positions, untimed
      refit.mode = runtime::RefitMode::kPivotFrame;
      if (runtime::Status s = refit.Run(); runtime::Failed(s)) return RuntimeFailure("refit", s);
      const runtime::SphereArrays v = workspace_.spheres();
      reference_.assign(v.x, v.x + v.count);
      reference_.insert(reference_.end(), v.y, v.y + v.count);
      reference_.insert(reference_.end(), v.z, v.z + v.count);
      reference_.insert(reference_.end(), v.r, v.r + v.count);
      frame_.reference = reference_;
    }
    runtime::JointRefitJob joints;
    joints.model = &model_;
    joints.workspace = &workspace_;
    joints.joint_matrices = joint_matrices;
    joints.joint_count = view_.asset->joint_count();
    if (runtime::Status s = Time(repeat_, [&] { return joints.Run(); }, &frame_.refit_us); runtime::Failed(s))
      return RuntimeFailure("joint refit", s);
  } else if (runtime::Status s = Time(repeat_, [&] { return refit.Run(); }, &frame_.refit_us); runtime::Failed(s)) {
    return RuntimeFailure("refit", s);
  }
  frame_.spheres = workspace_.spheres();
  return Ok{};
}

Status Session::Detect() {
  auto run = [&](runtime::DetectMethod method, std::vector<runtime::Collision>& out, runtime::DetectStats* stats,
                 double* us, std::span<const runtime::Collision>* pairs) -> Status {
    uint32_t count = 0;
    runtime::DetectJob job;
    job.model = &model_;
    job.workspace = &workspace_;
    job.method = method;
    job.output = out.data();
    job.capacity = static_cast<uint32_t>(out.size());
    job.count = &count;
    job.stats = stats;
    if (runtime::Status s = Time(repeat_, [&] { return job.Run(); }, us); runtime::Failed(s))
      return RuntimeFailure("detect", s);
    *pairs = {out.data(), count};
    return Ok{};
  };
  if (options_.m1) {
    if (auto s = run(runtime::DetectMethod::kM1, out_m1_, &frame_.m1_stats, &frame_.detect_m1_us, &frame_.m1); !s.ok())
      return s;
  }
  if (options_.m2) {
    if (auto s = run(runtime::DetectMethod::kM2, out_m2_, &frame_.m2_stats, &frame_.detect_m2_us, &frame_.m2); !s.ok())
      return s;
  }
  return Ok{};
}

Status Session::Narrow(const float* positions, const float* joint_matrices) {
  uint32_t count = 0;
  runtime::NarrowPhaseJob job;
  job.model = model_.narrow_phase();
  job.workspace = workspace_.narrow_phase();
  job.positions = {positions, view_.vertex_count, 12};
  job.exclusions = exclusions_;
  job.count = &count;
  job.stats = &frame_.narrow;
  const bool crease = exclusions_ == runtime::Exclusions::kCrease;
  // Behind the spheres' pairs: M2 with the wider margin, then the narrow phase on those pairs (timed together).
  const bool behind = options_.narrow == SessionNarrow::kBehindM2;
  if (!behind && crease && joint_matrices && job.model->has_joint_cull()) {
    // The frame was skinned by these matrices (Animation::Frame: linear blend of the mesh's own weights).
    job.joint_matrices = joint_matrices;
    job.joint_count = job.model->joint_count();
  }
  auto run = [&] {
    if (behind) {  // M2's pairs, and under the crease rule the proxy's folds
      const runtime::Status s =
          BehindPairs(view_, model_, workspace_, crease ? job.model : nullptr,
                      options_.narrow_behind_margin * model_.contact_margin(),
                      options_.fold_closing * model_.contact_margin(), &out_behind_, &frame_.behind_pairs,
                      &frame_.behind_folds);
      if (runtime::Failed(s)) return s;
      job.sphere_pairs = out_behind_.data();
      job.sphere_pair_count = frame_.behind_pairs;
    }
    return job.Run();
  };
  runtime::Status s;
  for (;;) {  // grow_contacts: the only bound is the job's budget, so the buffer grows until every contact fits
    job.output = contacts_.data();
    job.capacity = static_cast<uint32_t>(contacts_.size());
    if (crease) depths_.resize(contacts_.size()), job.depths = depths_.data();
    s = Time(repeat_, run, &frame_.narrow_us);
    if (runtime::Failed(s)) return RuntimeFailure("narrow phase", s);
    if (!runtime::IsTruncated(s) || !options_.grow_contacts) break;
    contacts_.resize(std::max<size_t>(2 * contacts_.size(), frame_.narrow.contacts));
  }
  frame_.narrow_status = s;
  frame_.contacts = {contacts_.data(), count};
  if (crease) frame_.depths = {depths_.data(), count};
  return Ok{};
}

runtime::Status BehindPairs(const runtime::AssetView& view, const runtime::Model& model, runtime::Workspace& workspace,
                            const runtime::NarrowPhaseModel* narrow, float margin, float closing,
                            std::vector<runtime::Collision>* out, uint32_t* count, uint32_t* folds) {
  *count = 0, *folds = 0;
  const size_t need =
      size_t{runtime::DetectBound(view, runtime::DetectMethod::kM2)} + (narrow ? narrow->fold_pair_count() : 0);
  if (out->size() < need) out->resize(need);
  runtime::DetectJob broad;
  broad.model = &model;
  broad.workspace = &workspace;
  broad.method = runtime::DetectMethod::kM2;
  broad.output = out->data();
  broad.capacity = static_cast<uint32_t>(out->size());
  uint32_t pairs = 0;
  broad.count = &pairs;
  broad.margin = margin;
  // One margin for every pair: the fold margin only keeps the spheres alone from crying wolf at a folding
  // joint, and the exact narrow phase behind them cannot cry wolf.
  if (model.fold_margin() >= 0.0f) broad.fold_margin = margin;
  if (const runtime::Status s = broad.Run(); runtime::Failed(s)) return s;
  if (narrow) {
    const runtime::Status s = runtime::FoldPairs(*narrow, workspace.spheres(), closing, out->data() + pairs,
                                                 static_cast<uint32_t>(out->size()) - pairs, folds);
    if (runtime::Failed(s)) return s;
  }
  *count = pairs + *folds;
  return runtime::Status::kOk;
}

}  // namespace spherechain::playback
