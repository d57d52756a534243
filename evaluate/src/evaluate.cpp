// Evaluate() (evaluate.h): the options, the context, the frame loop over playback::Session's frames, the
// picture. The stages a frame goes through are in evaluate_*.cpp (evaluate_internal.h lists them).
#include "spherechain/evaluate/evaluate.h"
#include "spherechain/evaluate/check.h"  // BodyHeight

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <tuple>

#include "evaluate_internal.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/debug_export.h"

namespace spherechain::evaluate {

using namespace detail;

namespace detail {

void Appendf(std::string* out, const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  if (n > 0) {
    const size_t at = out->size();
    out->resize(at + size_t(n) + 1);
    std::vsnprintf(out->data() + at, size_t(n) + 1, format, again);
    out->resize(at + size_t(n));
  }
  va_end(again);
}

int Context::SphereRegion(uint32_t s) const {
  const auto* sphere_regions = view.asset->sphere_regions();
  const int r = sphere_regions ? int(sphere_regions->Get(s)) : -1;
  return r >= 0 && size_t(r) < region_map.size() ? region_map[size_t(r)] : r;
}

bool Context::SkinNear(uint32_t ta, uint32_t tb) {
  const uint32_t* ia = &mesh.indices[3 * size_t{ta}];
  const uint32_t* ib = &mesh.indices[3 * size_t{tb}];
  return skin_scratch.Near(skin_graph, ia, ib, float(skin_crease));
}

import::Status Context::Init() {
  // The frame pipeline: refit (a.refit), M1 and M2 with the asset's margins, and the narrow phase over every
  // pair with the asset's exclusions (the truth's definition), its contacts kept up to 2^20; the reach
  // regions' model for the narrow phase behind the proxy's pairs.
  playback::SessionOptions so;
  so.refit = a.refit == "paper" ? playback::PlayRefit::kPaper
             : a.refit == "joints" ? playback::PlayRefit::kJoints
                                   : playback::PlayRefit::kPivotFrame;
  so.narrow = playback::SessionNarrow::kEvery;
  so.crease = false;
  so.reach_model = true;
  so.joint_matrices = true;  // the skin contacts' narrow phase culls with them (an asset with skin weights)
  so.contact_capacity = 1u << 20;
  if (auto s = session.Init(view, mesh, so); !s.ok()) return Fail(s.error().code, "'" + a.asset_name + "': " + s.error().message);
  contacts.resize(so.contact_capacity);
  out_m1.resize(runtime::DetectBound(view, runtime::DetectMethod::kM1));
  out_m2.resize(runtime::DetectBound(view, runtime::DetectMethod::kM2));

  V = view.vertex_count, T = view.triangle_count;
  crease_job = narrow().has_crease();
  weld.resize(V);
  for (uint32_t v = 0; v < V; ++v) weld[v] = narrow().weld_id(v);
  // --regions paper: an extended-layout asset (head, hands, feet) scored on the paper's five regions — a hand
  // counts as its arm, a foot as its leg, the head as the torso — so its recall and false alarms compare
  // with a paper-layout asset's (finer regions make a region pair's "nothing within the margin" stricter).
  if (a.paper_regions && view.asset->regions() && view.asset->biped()) {
    const auto* regions = view.asset->regions();
    const int trunk = int(regions->size()) - 1;
    for (int r = 0; r < int(regions->size()); ++r) {
      int q = r;
      if (r == trunk) q = 4;
      else if (r >= 4) q = regions->Get(r)->parent() >= 0 ? regions->Get(r)->parent() : 4;
      region_map.push_back(q);
    }
  }
  // Triangles by the region of their owning sphere, and by the sphere (for the false-alarm distance tests).
  sphere_triangles.resize(view.asset->spheres()->size());
  for (uint32_t t = 0; t < T; ++t)
    if (const uint32_t s = narrow().triangle_sphere(t); s != 0xFFFF) {
      region_triangles[SphereRegion(s)].push_back(t);
      if (s < sphere_triangles.size()) sphere_triangles[s].push_back(t);
    }
  height = BodyHeight(mesh), margin = a.margin_rel * height, crease = a.crease_rel * height;
  bind_centroid.resize(T);
  for (uint32_t t = 0; t < T; ++t) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k)
      sum += Eigen::Vector3d(mesh.positions[3 * mesh.indices[3 * t + k]], mesh.positions[3 * mesh.indices[3 * t + k] + 1],
                             mesh.positions[3 * mesh.indices[3 * t + k] + 2]);
    bind_centroid[t] = sum / 3.0;
  }
  // The skin's definition on the mesh alone (its own weld ids and bind positions; no asset data): the
  // crease is --crease of the height, or the asset's when larger (a job may only widen the asset's).
  skin_crease = std::max(crease, crease_job ? double(narrow().crease()) : 0.0);
  mesh_weld = import::ComputeWeldIds(mesh.positions);
  if (runtime::Status s = skin_graph.Init(mesh.positions.data(), V, mesh.indices.data(), T, mesh_weld.data(),
                                          float(skin_crease));
      runtime::Failed(s) || runtime::Failed(s = skin_scratch.Init(skin_graph)))
    return Fail(std::string("the crease rule's graph: ") + runtime::ToString(s));
  auto bind = baker::ExactSelfIntersections(mesh.positions.data(), V, mesh.indices, mesh_weld);
  if (!bind.ok()) return Fail(import::Error{bind.error().code, "bind pose: " + bind.error().message});
  for (const baker::TrianglePair& p : bind.value())
    if (!SkinNear(p.a, p.b)) skin_at_bind.insert(p);
  return import::Ok{};
}

uint32_t WorstFrame(const std::vector<FrameEval>& rows) {
  uint32_t worst = 0;
  // Ties (every frame found whole, say) go to the frame with the most contacts: a picture with something in it.
  const auto misses = [](const FrameEval& x) {
    return std::tuple(x.missed_contacts, x.missed_sphere_contacts, x.contacts);
  };
  for (uint32_t f = 0; f < rows.size(); ++f)
    if (misses(rows[f]) > misses(rows[worst])) worst = f;
  return worst;
}

}  // namespace detail

namespace {

/// The option limits Evaluate documents (kConfig).
import::Status CheckEvaluateOptions(const runtime::AssetView& view, const import::Mesh& mesh, const EvaluateOptions& a) {
  if (!(a.margin_rel >= 0.0 && a.margin_rel < 1.0))
    return Fail(Code::kConfig, "--margin must be in [0, 1) (a fraction of the body height)");
  if (!(a.crease_rel >= 0.0 && a.crease_rel <= 1.0))
    return Fail(Code::kConfig, "--crease must be in [0, 1] (a fraction of the body height)");
  if (a.refit != "paper" && a.refit != "frame" && a.refit != "joints")
    return Fail(Code::kConfig, "--refit '" + a.refit + "': expected paper, frame or joints");
  if (!view.valid()) return Fail(Code::kConfig, "'" + a.asset_name + "' is not a loaded asset");
  if (a.paper_regions && view.asset->regions() && !view.asset->biped())
    return Fail(Code::kConfig, "--regions paper: '" + a.asset_name + "' is a creature (" +
                                   std::to_string(view.asset->regions()->size()) +
                                   " regions of its own skeleton), not a biped: it has no paper regions to map onto");
  for (double m : a.sweep_margins_rel)
    if (!(m >= 0.0 && m <= 0.1))
      return Fail(Code::kConfig, "--sweep-margin: " + std::to_string(m) + " is not a margin in [0, 0.1] (a fraction of the body height)");
  // --refit joints: the spheres a GPU-skinned game gets (JointRefitJob: linear blend skinning of the
  // centres by the frame's skinning matrices), judged against the same truth.
  if (a.refit == "joints" && !view.asset->sphere_joints())
    return Fail(Code::kConfig, "'" + a.asset_name + "' has no joint weights (schema v" + std::to_string(view.asset->schema_version()) +
                ", or baked from a mesh without a skin): --refit joints needs an asset baked from a rigged character");
  if (a.refit == "joints" && (!mesh.skin || view.asset->joint_count() != mesh.skin->joints.size()))
    return Fail(Code::kConfig, "'" + a.asset_name + "' was baked for " + std::to_string(view.asset->joint_count()) + " joints, '" +
                a.mesh_name + "' has " + std::to_string(mesh.skin ? mesh.skin->joints.size() : 0));
  return import::Ok{};
}

/// Every stage of one frame, in order, into `row` (and the sweep's sums).
import::Status EvaluateFrame(Context& c, const playback::SessionFrame& fr, FrameEval* row, std::vector<SweepPoint>* sweep) {
  row->label = fr.label;
  if (c.a.coverage)
    if (auto s = MeasureRefitCoverage(c, fr, row); !s.ok()) return s;
  RecordProxyPairs(c, fr, row);
  std::set<baker::TrianglePair> narrow_pairs, behind[2], behind_reach[2];
  RecordNarrowPhase(c, fr, row, &narrow_pairs);
  if (auto s = RunBehindTheProxy(c, fr, row, behind, behind_reach); !s.ok()) return s;
  auto exact = ExactTruth(c, fr, row);
  if (!exact.ok()) return exact.error();
  if (auto s = MeasureSkinContacts(c, fr, exact.value(), behind_reach, row); !s.ok()) return s;
  std::vector<baker::TrianglePair> contact_pairs;
  ClassifyIntersections(c, exact.value(), narrow_pairs, behind, behind_reach, row, &contact_pairs);
  if (auto s = LocaliseContacts(c, fr, contact_pairs, row); !s.ok()) return s;
  NearCache cache;
  if (auto s = MeasureFalseAlarms(c, fr, &cache, row); !s.ok()) return s;
  if (auto s = SweepMargins(c, fr, *row, &cache, sweep); !s.ok()) return s;
  if (!c.a.png_path.empty()) {
    const runtime::SphereArrays& sp = fr.spheres;
    for (uint32_t s = 0; s < sp.count; ++s) row->spheres.insert(row->spheres.end(), {sp.x[s], sp.y[s], sp.z[s], sp.r[s]});
  }
  return import::Ok{};
}

/// The picture of frame `f` (the one with the most missed contacts): its contact triangles red (missed by M2's
/// sphere pairs) or amber (found), and the frame's refit spheres.
import::Status Picture(const Context& c, const std::vector<FrameEval>& rows, uint32_t f) {
  std::string label;
  std::vector<float> positions;
  playback::SkinningScratch scratch;
  if (auto s = c.anim.Frame(c.mesh, f, &scratch, &positions, &label); !s.ok()) return s;
  auto exact = baker::ExactSelfIntersections(positions.data(), c.V, c.mesh.indices, c.weld);
  if (!exact.ok()) return Fail(exact.error());
  std::vector<uint8_t> marks(c.T, 0);
  for (const baker::TrianglePair& p : exact.value()) {
    const uint32_t sa = c.narrow().triangle_sphere(p.a), sb = c.narrow().triangle_sphere(p.b);
    if (sa == 0xFFFF || sb == 0xFFFF || sa == sb || c.narrow().IsExcluded(sa, sb)) continue;
    const bool found = rows[f].m2_spheres.count({std::min(sa, sb), std::max(sa, sb)}) > 0;
    for (uint32_t t : {p.a, p.b}) marks[t] = std::max<uint8_t>(marks[t], found ? 2 : 1);
  }
  const std::vector<float>& sp = rows[f].spheres;
  const auto* sphere_regions = c.view.asset->sphere_regions();
  std::vector<playback::FrameSphere> spheres;
  for (uint32_t s = 0; 4 * s < sp.size(); ++s)  // coloured by the asset's own regions, as the triangles are
    spheres.push_back({{sp[4 * s], sp[4 * s + 1], sp[4 * s + 2]}, sp[4 * s + 3],
                       playback::RegionColor(c.view, sphere_regions ? uint32_t(sphere_regions->Get(s)) : 0u), 0.35f});
  std::string caption;
  detail::Appendf(&caption, "frame %u (%s): %u contacts, %u missed by the proxy's sphere pairs (red), the rest found (amber); "
                            "refit spheres (M2)",
                  f, label.c_str(), rows[f].contacts, rows[f].missed_sphere_contacts);
  return playback::SvgToPng(playback::RenderFrameSvg(c.mesh, c.view, positions.data(), spheres, marks, caption),
                            c.a.png_path);
}

}  // namespace

import::Status ParseSweepMargins(const std::string& text, std::vector<double>* out) {
  out->clear();
  if (text.empty()) return import::Ok{};
  if (text == "auto") {
    out->assign(std::begin(kDefaultSweepMargins), std::end(kDefaultSweepMargins));
    return import::Ok{};
  }
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !(v >= 0.0 && v <= 0.1))
      return Fail(Code::kConfig, "--sweep-margin: '" + item + "' is not a margin in [0, 0.1] (a fraction of the body height)");
    out->push_back(v);
    start = comma + 1;
  }
  std::sort(out->begin(), out->end());
  out->erase(std::unique(out->begin(), out->end()), out->end());
  return import::Ok{};
}

import::Result<Evaluation> Evaluate(const runtime::AssetView& view, const import::Mesh& mesh,
                                    const playback::Animation& anim, const EvaluateOptions& a, import::Context* log_in) {
  if (auto s = CheckEvaluateOptions(view, mesh, a); !s.ok()) return s.error();
  std::vector<SweepPoint> sweep;
  for (double m : a.sweep_margins_rel) sweep.push_back({m});
  import::Context no_log;
  Context c(view, mesh, anim, a, log_in ? *log_in : no_log);
  if (auto s = c.Init(); !s.ok()) return s.error();

  // Every frame through the pipeline (animate, refit, M1, M2, the narrow phase), then the frame's measures.
  std::vector<FrameEval> rows(anim.frames);
  const auto t_start = std::chrono::steady_clock::now();
  auto played = c.session.Play(anim, [&](const playback::SessionFrame& fr) -> import::Status {
    if (auto s = EvaluateFrame(c, fr, &rows[fr.frame], &sweep); !s.ok()) return s;
    if (a.progress)
      a.progress(fr.frame + 1, anim.frames,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
    return import::Ok{};
  });
  if (!played.ok()) return Fail(played.error());

  auto bind_coverage = MeasureBindCoverage(c);
  if (!bind_coverage.ok()) return bind_coverage.error();
  Evaluation result;
  Report(c, rows, sweep, bind_coverage.value(), &result);
  // Nothing is written before every frame succeeded.
  if (!a.png_path.empty()) {
    const uint32_t f = WorstFrame(rows);
    if (auto s = Picture(c, rows, f); !s.ok()) return Fail(s.error());
    result.png_frame = int(f);
  }
  return result;
}

}  // namespace spherechain::evaluate
