// runtime_bench — per-frame cost of spherechain refit + detect and of the narrow phase against peers
// doing the same work.
//
//   runtime_bench --synthetic [--frames N] [--reps R] [--runs K] [--narrow-only] [--cgal-frames N] [--per-frame]
//   runtime_bench ASSET.sphc FRAMES [--reps R] [--runs K] [--narrow-only] [--cgal-frames N] [--per-frame]
//                 [--behind-margins S,S,...]   ("behind M2's pairs" with DetectJob's margin S × the asset's; default 1)
//   runtime_bench ASSET.sphc FRAMES --geodesics N   (the crease rule's Dijkstra against exact geodesics, CGAL
//                                                   Surface_mesh_shortest_path, from N bind-pose vertices; then exits)
//   runtime_bench ASSET.sphc FRAMES --profile R   (refit + M1 over all frames R times, nothing else:
//                                                   for valgrind --tool=callgrind instruction counts)
//   runtime_bench ASSET.sphc FRAMES --batch-only [--characters N] [--runs K]   (only "many characters")
//     FRAMES: a .f32 file of #F×#V×3 little-endian float32 positions, or a folder of .f32 files (one
//     frame each, #V×3, sorted by name).
//
// Rows (median µs per frame over 5 rounds × frames of batches of R calls, one core; with --runs K the
// whole table is measured K times and each row keeps its best median — for a loaded machine):
//   sc refit            RefitJob (kPivotFrame), §5.1
//   sc M1 detect        DetectJob M1 (chains, §5.2) on stored spheres — the paper's method
//   sc refit+M1         RefitJob + DetectJob M1
//   sc M2 detect        DetectJob M2 (all spheres) on stored spheres
//   sc refit+M2         RefitJob + DetectJob M2
//   sc M1/M2 det. fold mrg  the same detections with the asset's fold margin (only for an asset with one; the rows
//                       above then test every pair on the contact margin, as the peers do)
//   naive M2            AoS double loop + exclusion matrix over the refitted spheres
//   FCL DynAABBTree M2  fcl::DynamicAABBTreeCollisionManager, spheres updated, collide + sphere test
//   Bullet btDbvt M2    btDbvtBroadphase, AABBs updated, overlapping pairs then the sphere test
// "broad phase per frame": DetectStats::box_tests and sphere_tests of DetectJob (means over the frames).
// Peers get the refitted spheres (refit not included) and apply the same excluded pairs; their pair
// counts are checked against DetectJob M2 every frame, and M1's against a naive loop over the pairs
// sharing a chain. Ratios: peer / sc M2 detect (the same all-pairs work) and peer / sc refit+M1 (the
// per-frame cost of the paper's pipeline against the peer's broad phase alone).
//
// Section "narrow phase" (skip the sphere rows with --narrow-only): NarrowPhaseJob::Run (asset
// exclusions, 2^20 contacts of capacity) on every frame, each frame the fastest of K passes over the
// frames in turn: time, candidate sphere pairs, exact triangle tests against all #T(#T−1)/2 pairs,
// contacts; a breakdown (region boxes: Run on an empty pair list; exact tests: PrepareTriangle on each
// triangle of, then TrianglesIntersect on the prepared, pairs of a bench-side replica of the tested
// pairs, which must match stats.triangle_tests and contacts, alone; the rest: candidates, triangle
// boxes, culling, box tests). Peer: CGAL PMP::self_intersections (sequential) on a
// Surface_mesh of the asset's triangles over welded vertices, first N frames (--cgal-frames, default
// 10; 0 = off), 1 run each. CGAL reports every self-intersection; its pairs are split into what our
// contact definition leaves out (degenerate faces, same region, excluded sphere pairs, no region) and
// the rest, which is compared with our contacts (printed, never fails the run). The same CGAL pairs under
// the skin's definition (no welded corner in common, not near by the crease rule) must equal the
// skin-contact job's contacts on those frames (a mismatch fails the run); the ratio CGAL / that job is
// printed without and with the joint matrices. --per-frame: one line per frame (time, breakdown,
// counters), for the narrow phase and for the skin contacts. "behind M2's pairs": per frame RefitJob +
// DetectJob M2, then NarrowPhaseJob restricted to those pairs on the surrounding regions' and on the
// reach regions' model (NarrowPhaseRegions), timed, with the share of the frame's contacts each finds
// (a contact the unrestricted job did not report fails the run).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <numeric>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "runtime/asset_builder.h"
#include "spherechain/runtime/runtime.h"
#include "spherechain/runtime/triangle_intersect.h"

#if SPHERECHAIN_BENCH_TBB
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#endif
#if SPHERECHAIN_BENCH_FCL
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision_object.h>
#endif
#if SPHERECHAIN_BENCH_BULLET
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#endif
#if SPHERECHAIN_BENCH_EMBREE
#include <embree3/rtcore.h>
#endif
#if SPHERECHAIN_BENCH_CGAL
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_shortest_path.h>
#endif

namespace sc = spherechain::runtime;
namespace test = spherechain::test;

namespace {

struct Workload {
  test::AlignedBytes bytes;
  uint32_t vertex_count = 0;
  std::vector<std::vector<float>> frames;  // #F × (#V×3)
  std::vector<std::vector<float>> joints;  // [opt] #F × (#J×12): frame_NNNN.joints beside frame_NNNN.f32
};

// ~ the paper's workload: 80 spheres, 6 chains of 22–23 (Table 1 pairs the four limbs), limbs swinging.
Workload Synthetic(uint32_t frame_count) {
  Workload w;
  test::Mesh mesh;
  std::vector<test::Tube> tubes;
  const float dirs[4][3] = {{0.8f, 0.6f, 0}, {-0.8f, 0.6f, 0}, {0.3f, -0.954f, 0}, {-0.3f, -0.954f, 0}};
  for (int l = 0; l < 4; ++l) {  // limbs, 11 spheres
    test::Tube t;
    t.rings = 11;
    for (int k = 0; k < 3; ++k) t.direction[k] = dirs[l][k];
    t.origin[0] = 0.6f * dirs[l][0];
    t.origin[1] = 0.6f * dirs[l][1];
    tubes.push_back(t);
  }
  for (int g = 0; g < 4; ++g) {  // torso: 4 columns of 9 (L, R, T, D groups)
    test::Tube t;
    t.rings = 9;
    t.direction[0] = 0;
    t.direction[1] = 1;
    t.origin[0] = -3.3f + 2.2f * float(g);
    t.origin[1] = -5.0f;
    t.origin[2] = -2.5f;
    tubes.push_back(t);
  }
  // Table 1 shape: each chain joins two limbs and a torso group (sizes 22 + a share of the torso).
  test::AssetData d = test::MakeTubes(tubes, {{0, 2}, {1, 3}, {0, 1, 6}, {2, 3, 7}, {0, 3}, {1, 2}}, &mesh);
  w.bytes = test::Serialize(d);
  w.vertex_count = mesh.vertex_count();
  // Animation: each limb swings about the z axis through its root, a different phase per limb.
  uint32_t first_vertex[9] = {0};
  for (size_t t = 0; t < tubes.size(); ++t) first_vertex[t + 1] = first_vertex[t] + tubes[t].rings * tubes[t].sides;
  for (uint32_t f = 0; f < frame_count; ++f) {
    std::vector<float> p = mesh.positions;
    for (int l = 0; l < 4; ++l) {
      const float a = 1.2f * std::sin(6.2831853f * float(f) / float(frame_count) + float(l));
      const float c = std::cos(a), s = std::sin(a);
      for (uint32_t v = first_vertex[l]; v < first_vertex[l + 1]; ++v) {
        const float x = p[3 * v] - tubes[l].origin[0], y = p[3 * v + 1] - tubes[l].origin[1];
        p[3 * v] = tubes[l].origin[0] + c * x - s * y;
        p[3 * v + 1] = tubes[l].origin[1] + s * x + c * y;
      }
    }
    w.frames.push_back(std::move(p));
  }
  return w;
}

// A raw frame file (play --dump-frames); the asset goes through test::ReadAlignedFile.
bool ReadFile(const std::string& path, std::vector<char>* out) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  out->assign(std::istreambuf_iterator<char>(f), {});
  return true;
}

bool FromFiles(const std::string& asset, const std::string& frames, Workload* w) {
  if (!test::ReadAlignedFile(asset, &w->bytes)) return std::fprintf(stderr, "cannot read %s\n", asset.c_str()), false;
  std::vector<char> raw;
  sc::AssetView view;
  if (sc::Status s = sc::LoadAsset(w->bytes.data(), w->bytes.size, &view); s != sc::Status::kOk)
    return std::fprintf(stderr, "%s: %s\n", asset.c_str(), sc::ToString(s)), false;
  w->vertex_count = view.vertex_count;
  const size_t per_frame = size_t{view.vertex_count} * 3;
  std::vector<std::string> files;
  if (std::filesystem::is_directory(frames)) {
    for (const auto& e : std::filesystem::directory_iterator(frames))
      if (e.path().extension() == ".f32") files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
  } else {
    files.push_back(frames);
  }
  // Joint matrices (play --dump-frames writes frame_NNNN.joints for an asset with joint weights): all
  // frames' or none.
  const uint32_t J = view.asset->sphere_joints() ? view.asset->joint_count() : 0;
  bool all_joints = J > 0 && std::filesystem::is_directory(frames);
  for (const std::string& file : files)
    all_joints = all_joints && std::filesystem::exists(std::filesystem::path(file).replace_extension(".joints"));
  for (const std::string& file : files) {
    if (all_joints) {
      const std::string jf = std::filesystem::path(file).replace_extension(".joints").string();
      if (!ReadFile(jf, &raw) || raw.size() != size_t{J} * 12 * 4)
        return std::fprintf(stderr, "%s: not #J×12 float32 (#J = %u)\n", jf.c_str(), J), false;
      std::vector<float> m(size_t{J} * 12);
      std::memcpy(m.data(), raw.data(), raw.size());
      w->joints.push_back(std::move(m));
    }
    if (!ReadFile(file, &raw) || raw.size() % (per_frame * 4) != 0 || raw.empty())
      return std::fprintf(stderr, "%s: not a multiple of #V×3 float32 (#V = %u)\n", file.c_str(), view.vertex_count), false;
    for (size_t off = 0; off < raw.size(); off += per_frame * 4) {
      std::vector<float> p(per_frame);
      std::memcpy(p.data(), raw.data() + off, per_frame * 4);
      w->frames.push_back(std::move(p));
    }
  }
  return !w->frames.empty();
}

// Median over batches of `reps` calls of fn(frame), per call, in µs.
double MedianMicros(size_t frames, int reps, const std::function<void(size_t)>& fn) {
  std::vector<double> samples;
  for (int round = 0; round < 5; ++round)
    for (size_t f = 0; f < frames; ++f) {
      const auto t0 = std::chrono::steady_clock::now();
      for (int r = 0; r < reps; ++r) fn(f);
      const auto t1 = std::chrono::steady_clock::now();
      samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count() / reps);
    }
  std::nth_element(samples.begin(), samples.begin() + samples.size() / 2, samples.end());
  return samples[samples.size() / 2];
}

volatile uint32_t g_sink = 0;

// ---------------------------------------------------------------------------------------------------
// Narrow phase: NarrowPhaseJob on every frame, CGAL self_intersections on the first frames.

using Clock = std::chrono::steady_clock;

template <class Fn>
double Micros(Fn&& fn) {
  const auto t0 = Clock::now();
  fn();
  return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
}

struct Summary {
  double mean = 0, median = 0, max = 0;
  size_t argmax = 0;
};

Summary Summarize(const std::vector<double>& v) {
  Summary s;
  if (v.empty()) return s;
  for (size_t i = 0; i < v.size(); ++i) {
    s.mean += v[i] / double(v.size());
    if (v[i] > s.max) s.max = v[i], s.argmax = i;
  }
  std::vector<double> sorted = v;
  std::sort(sorted.begin(), sorted.end());
  const size_t n = sorted.size();
  s.median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  return s;
}

template <class Field>
std::vector<double> Column(const std::vector<sc::NarrowPhaseStats>& stats, Field field) {
  std::vector<double> v;
  for (const sc::NarrowPhaseStats& s : stats) v.push_back(double(s.*field));
  return v;
}

using TrianglePair = std::pair<uint32_t, uint32_t>;  // source triangle indices, first < second

// What one asset's narrow phase sees, for the bench-side replica and the CGAL classification.
struct NarrowAsset {
  const sc::NarrowPhaseModel* context;  // the per-asset data: weld ids, owners, exclusions
  const uint32_t* triangles;  // Asset.triangles, #T×3
  uint32_t triangle_count;
  bool Adjacent(uint32_t s, uint32_t t) const {  // a welded corner in common
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (context->weld_id(triangles[3 * s + i]) == context->weld_id(triangles[3 * t + j])) return true;
    return false;
  }
  bool IndexDegenerate(uint32_t t) const {
    const uint32_t a = context->weld_id(triangles[3 * t]), b = context->weld_id(triangles[3 * t + 1]),
                   c = context->weld_id(triangles[3 * t + 2]);
    return a == b || b == c || a == c;
  }
  const float* Corner(const float* positions, uint32_t t, int k) const {
    return positions + 3 * size_t{triangles[3 * t + k]};
  }
};

// The triangle pairs NarrowPhaseJob::Run hands to TrianglesIntersect, found independently: triangles
// of a surrounding region, not (index or exactly) degenerate, owned by different, non-excluded spheres,
// closed boxes overlapping, no welded corner in common. Sweep and prune on the longest axis. Sorted.
std::vector<TrianglePair> TestedPairs(const NarrowAsset& m, const float* positions) {
  struct Box {
    float lo[3], hi[3];
    uint32_t t;
    uint16_t sphere;
  };
  std::vector<Box> boxes;
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (uint32_t t = 0; t < m.triangle_count; ++t) {
    const uint16_t s = m.context->triangle_sphere(t);
    if (s == 0xFFFF || m.IndexDegenerate(t)) continue;
    const float *p = m.Corner(positions, t, 0), *q = m.Corner(positions, t, 1), *r = m.Corner(positions, t, 2);
    if (sc::TriangleIsDegenerate(p, q, r)) continue;
    Box b;
    for (int k = 0; k < 3; ++k) {
      b.lo[k] = std::min(std::min(p[k], q[k]), r[k]);
      b.hi[k] = std::max(std::max(p[k], q[k]), r[k]);
      lo[k] = std::min(lo[k], b.lo[k]);
      hi[k] = std::max(hi[k], b.hi[k]);
    }
    b.t = t;
    b.sphere = s;
    boxes.push_back(b);
  }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  std::sort(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) { return a.lo[axis] < b.lo[axis]; });
  std::vector<TrianglePair> pairs;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const Box& a = boxes[i];
    for (size_t j = i + 1; j < boxes.size() && boxes[j].lo[axis] <= a.hi[axis]; ++j) {
      const Box& b = boxes[j];
      if (a.sphere == b.sphere) continue;
      bool overlap = true;
      for (int k = 0; k < 3; ++k) overlap &= a.lo[k] <= b.hi[k] && b.lo[k] <= a.hi[k];
      if (!overlap || m.context->IsExcluded(a.sphere, b.sphere) || m.Adjacent(a.t, b.t)) continue;
      pairs.emplace_back(std::min(a.t, b.t), std::max(a.t, b.t));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

#if SPHERECHAIN_BENCH_CGAL
namespace PMP = CGAL::Polygon_mesh_processing;
using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Epick::Point_3>;

// The asset's triangles as a CGAL surface mesh over the welded vertices (seams closed, so CGAL's
// topological adjacency is ours), index-degenerate triangles left out. Built once; per frame only the
// points change.
struct CgalPeer {
  CgalMesh mesh;
  std::vector<uint32_t> vertex_source;  // mesh vertex → source vertex (a weld representative)
  std::vector<uint32_t> face_source;    // mesh face → source triangle
  size_t duplicated_points = 0;         // added by orient_polygon_soup (non-manifold vertices)
  bool oriented = true;                 // orient_polygon_soup's answer

  // Empty string on success, else why the soup could not become a surface mesh.
  std::string Build(const NarrowAsset& m, uint32_t vertex_count) {
    // Point i carries its source index in x: orient_polygon_soup only copies points (combinatorial),
    // so every point it appends still says where it came from.
    std::vector<Epick::Point_3> points(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v) points[v] = Epick::Point_3(double(v), 0, 0);
    std::vector<std::vector<std::size_t>> polygons;
    for (uint32_t t = 0; t < m.triangle_count; ++t) {
      if (m.IndexDegenerate(t)) continue;
      polygons.push_back({m.context->weld_id(m.triangles[3 * t]), m.context->weld_id(m.triangles[3 * t + 1]),
                          m.context->weld_id(m.triangles[3 * t + 2])});
      face_source.push_back(t);
    }
    oriented = PMP::orient_polygon_soup(points, polygons);
    duplicated_points = points.size() - vertex_count;
    if (polygons.size() != face_source.size()) return "orient_polygon_soup changed the polygon count";
    if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) return "not a polygon mesh after orient_polygon_soup";
    PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);  // vertex i = point i, face i = polygon i
    if (mesh.number_of_vertices() != points.size() || mesh.number_of_faces() != polygons.size())
      return "polygon_soup_to_polygon_mesh did not keep one vertex per point and one face per polygon";
    for (CgalMesh::Vertex_index v : mesh.vertices())
      vertex_source.push_back(static_cast<uint32_t>(mesh.point(v).x()));
    return {};
  }

  void SetFrame(const float* positions) {
    for (CgalMesh::Vertex_index v : mesh.vertices()) {
      const float* p = positions + 3 * size_t{vertex_source[v.idx()]};
      mesh.point(v) = Epick::Point_3(p[0], p[1], p[2]);
    }
  }
};

// CGAL's pairs of one frame, sorted into what our definition leaves out and what it keeps.
struct CgalClasses {
  size_t all = 0, degenerate = 0, unassigned = 0, same_region = 0, excluded = 0, weld_adjacent = 0;
  std::vector<TrianglePair> ours;  // different, non-excluded spheres, no welded corner in common; sorted
};

CgalClasses Classify(const NarrowAsset& m, const CgalPeer& peer,
                     const std::vector<std::pair<CgalMesh::Face_index, CgalMesh::Face_index>>& pairs) {
  CgalClasses c;
  c.all = pairs.size();
  for (const auto& [f, g] : pairs) {
    if (f == g) {  // CGAL reports a degenerate face as (f, f) and tests it against nothing else
      ++c.degenerate;
      continue;
    }
    const uint32_t s = peer.face_source[f.idx()], t = peer.face_source[g.idx()];
    const uint16_t a = m.context->triangle_sphere(s), b = m.context->triangle_sphere(t);
    if (a == 0xFFFF || b == 0xFFFF) ++c.unassigned;
    else if (a == b) ++c.same_region;
    else if (m.context->IsExcluded(a, b)) ++c.excluded;
    else if (m.Adjacent(s, t)) ++c.weld_adjacent;
    else c.ours.emplace_back(std::min(s, t), std::max(s, t));
  }
  std::sort(c.ours.begin(), c.ours.end());
  return c;
}
#endif

// Prints the "narrow phase behind M2's pairs" rows: per frame RefitJob (kPivotFrame) + DetectJob M2, then
// NarrowPhaseJob restricted to those pairs on the surrounding regions' model and on the reach regions'
// (NarrowPhaseRegions::kReach); the fastest of `runs` passes per frame, and how many of the frame's
// contacts (`all`, the unrestricted narrow phase's) each finds. Once per entry of `margin_scales`: DetectJob's
// margin that many times the asset's contact margin (the broad phase's margin an engine picks for the narrow
// phase; evaluate --sweep-margin gives the recall it buys). False when a restricted job reports a contact the
// unrestricted one does not.
bool BehindTheProxy(const Workload& w, const sc::AssetView& view, int runs,
                    const std::vector<std::vector<TrianglePair>>& all, float margin_scale) {
  sc::Model model;
  sc::Workspace ws;
  sc::NarrowPhaseModel np[2];
  sc::NarrowPhaseWorkspace np_ws[2];
  const sc::NarrowPhaseRegions kinds[2] = {sc::NarrowPhaseRegions::kSurrounding, sc::NarrowPhaseRegions::kReach};
  for (int k = 0; k < 2; ++k)
    if (np[k].Init(view, kinds[k]) != sc::Status::kOk || np_ws[k].Init(np[k]) != sc::Status::kOk) return true;
  if (model.Init(view) != sc::Status::kOk || ws.Init(model) != sc::Status::kOk) return true;
  const size_t F = w.frames.size();
  std::vector<sc::Collision> pairs(sc::DetectBound(view, sc::DetectMethod::kM2));
  std::vector<sc::TriangleContact> out(size_t{1} << 20);
  double median[2] = {0, 0}, worst[2] = {0, 0};
  size_t found[2] = {0, 0}, total = 0, reported = 0, tests[2] = {0, 0};
  bool ok = true;
  for (int k = 0; k < 2; ++k) {
    std::vector<double> us(F, 1e300);
    for (size_t f = 0; f < F; ++f) {
      sc::RefitJob refit;
      refit.model = &model;
      refit.workspace = &ws;
      refit.positions = {w.frames[f].data(), w.vertex_count, 12};
      uint32_t n_pairs = 0, n = 0;
      sc::DetectJob m2;
      m2.model = &model;
      m2.workspace = &ws;
      m2.method = sc::DetectMethod::kM2;
      m2.margin = margin_scale == 1.0f ? -1.0f : margin_scale * model.contact_margin();
      // One margin for every pair in front of the exact narrow phase (as play --narrow-behind).
      if (model.fold_margin() >= 0.0f) m2.fold_margin = margin_scale * model.contact_margin();
      m2.output = pairs.data();
      m2.capacity = static_cast<uint32_t>(pairs.size());
      m2.count = &n_pairs;
      if (sc::Failed(refit.Run()) || sc::Failed(m2.Run())) return false;
      sc::NarrowPhaseStats st;
      sc::NarrowPhaseJob job;
      job.model = &np[k];
      job.workspace = &np_ws[k];
      job.positions = refit.positions;
      job.sphere_pairs = pairs.data();
      job.sphere_pair_count = n_pairs;
      job.output = out.data();
      job.capacity = static_cast<uint32_t>(out.size());
      job.count = &n;
      job.stats = &st;
      for (int r = 0; r < runs; ++r) us[f] = std::min(us[f], Micros([&] { (void)job.Run(); }));
      tests[k] += st.triangle_tests;
      for (uint32_t i = 0; i < n; ++i) {
        const TrianglePair p{std::min(out[i].triangle_a, out[i].triangle_b), std::max(out[i].triangle_a, out[i].triangle_b)};
        if (!std::binary_search(all[f].begin(), all[f].end(), p)) ok = false;
      }
      found[k] += n;
      if (k == 0) total += all[f].size(), reported += n_pairs;
    }
    const Summary t = Summarize(us);
    median[k] = t.median, worst[k] = t.max;
  }
  std::printf("behind M2's pairs (RefitJob + DetectJob M2 with %g x the asset's margin, then NarrowPhaseJob restricted "
              "to the %.1f pairs a frame; fastest of %d):\n", double(margin_scale), F ? double(reported) / F : 0.0, runs);
  for (int k = 0; k < 2; ++k)
    std::printf("  %-20s median %7.1f us, max %7.1f us; %6.1f exact tests a frame; contacts found %zu of %zu (%.1f %%)\n",
                k == 0 ? "surrounding regions" : "reach regions", median[k], worst[k], F ? double(tests[k]) / F : 0.0,
                found[k], total, total ? 100.0 * found[k] / total : 100.0);
  if (!ok) std::fprintf(stderr, "MISMATCH: a restricted narrow phase reported a contact the unrestricted one did not\n");
  return ok;
}

// Prints the "narrow phase" section; false when a cross-check failed.
// A NarrowPhaseJob over all of `out` (its whole size as capacity), writing its count and stats.
sc::NarrowPhaseJob NarrowJob(const sc::NarrowPhaseModel& np, sc::NarrowPhaseWorkspace& ws, sc::Exclusions exclusions,
                             std::vector<sc::TriangleContact>& out, uint32_t* count, sc::NarrowPhaseStats* stats) {
  sc::NarrowPhaseJob job;
  job.model = &np;
  job.workspace = &ws;
  job.exclusions = exclusions;
  job.output = out.data();
  job.capacity = static_cast<uint32_t>(out.size());
  job.count = count;
  job.stats = stats;
  return job;
}

#if SPHERECHAIN_BENCH_EMBREE
// Intel Embree 3 as the skin contacts' peer: one thread, a user geometry of the deformed triangles' boxes
// (index-degenerate triangles left out) refit each frame (RTC_BUILD_QUALITY_REFIT), rtcCollide of the scene
// with itself, and in the callback what the job does after its boxes: pairs sharing a welded corner skipped,
// the exact test on prepared triangles, the crease rule asked of the graph (CreaseScratch::Near).
struct EmbreePeer {
  const sc::NarrowPhaseModel* np = nullptr;
  const uint32_t* tri = nullptr;
  const float* pos = nullptr;
  std::vector<uint32_t> prims;  // embree primitive → triangle
  std::vector<sc::PreparedTriangle> prepared;
  std::vector<int8_t> state;
  sc::CreaseScratch scratch;
  std::vector<TrianglePair>* out = nullptr;
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;
  uint64_t box_pairs = 0;

  static void Bounds(const RTCBoundsFunctionArguments* args) {
    const EmbreePeer& e = *static_cast<const EmbreePeer*>(args->geometryUserPtr);
    const uint32_t* v = e.tri + 3 * size_t{e.prims[args->primID]};
    RTCBounds& b = *args->bounds_o;
    const float* p0 = e.pos + 3 * size_t{v[0]};
    const float* p1 = e.pos + 3 * size_t{v[1]};
    const float* p2 = e.pos + 3 * size_t{v[2]};
    b.lower_x = std::min({p0[0], p1[0], p2[0]}), b.upper_x = std::max({p0[0], p1[0], p2[0]});
    b.lower_y = std::min({p0[1], p1[1], p2[1]}), b.upper_y = std::max({p0[1], p1[1], p2[1]});
    b.lower_z = std::min({p0[2], p1[2], p2[2]}), b.upper_z = std::max({p0[2], p1[2], p2[2]});
  }
  bool Ready(uint32_t t) {
    if (state[t] == 0) {
      const uint32_t* v = tri + 3 * size_t{t};
      state[t] = sc::PrepareTriangle(pos + 3 * size_t{v[0]}, pos + 3 * size_t{v[1]}, pos + 3 * size_t{v[2]}, &prepared[t]) ? 1 : 2;
    }
    return state[t] == 1;
  }
  static void Collide(void* user, RTCCollision* c, unsigned int n) {
    EmbreePeer& e = *static_cast<EmbreePeer*>(user);
    for (unsigned int i = 0; i < n; ++i) {
      uint32_t t = e.prims[c[i].primID0], u = e.prims[c[i].primID1];
      if (t == u) continue;
      if (t > u) std::swap(t, u);
      ++e.box_pairs;
      const uint32_t* tv = e.tri + 3 * size_t{t};
      const uint32_t* uv = e.tri + 3 * size_t{u};
      bool shared = false;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) shared |= e.np->weld_id(tv[a]) == e.np->weld_id(uv[b]);
      if (shared || !e.Ready(t) || !e.Ready(u) || !sc::TrianglesIntersect(e.prepared[t], e.prepared[u])) continue;
      if (e.scratch.Near(e.np->crease_graph(), tv, uv, e.np->crease())) continue;
      e.out->emplace_back(t, u);
    }
  }
  bool Init(const sc::NarrowPhaseModel& model, const uint32_t* triangles, uint32_t T) {
    np = &model;
    tri = triangles;
    for (uint32_t t = 0; t < T; ++t) {
      const uint32_t* v = tri + 3 * size_t{t};
      if (model.weld_id(v[0]) != model.weld_id(v[1]) && model.weld_id(v[1]) != model.weld_id(v[2]) &&
          model.weld_id(v[0]) != model.weld_id(v[2]))
        prims.push_back(t);
    }
    prepared.resize(T);
    state.assign(T, 0);
    if (scratch.Init(model.crease_graph()) != sc::Status::kOk) return false;
    device = rtcNewDevice("threads=1");
    if (!device) return false;
    scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_DYNAMIC);
    geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned int>(prims.size()));
    rtcSetGeometryUserData(geometry, this);
    rtcSetGeometryBoundsFunction(geometry, &Bounds, this);
    rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_REFIT);
    rtcAttachGeometry(scene, geometry);
    return true;
  }
  ~EmbreePeer() {
    if (geometry) rtcReleaseGeometry(geometry);
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  // One frame: the boxes refit (or built, the first time) and the self-collision. Returns the build time (µs).
  double Frame(const float* positions, std::vector<TrianglePair>* pairs) {
    pos = positions;
    out = pairs;
    pairs->clear();
    std::fill(state.begin(), state.end(), int8_t{0});
    scratch.Reset();
    const double build_us = Micros([&] {
      rtcCommitGeometry(geometry);
      rtcCommitScene(scene);
    });
    rtcCollide(scene, scene, &Collide, this);
    std::sort(pairs->begin(), pairs->end());
    pairs->erase(std::unique(pairs->begin(), pairs->end()), pairs->end());
    return build_us;
  }
};
#endif

// Skin contacts (Exclusions::kCrease): NarrowPhaseJob under the crease rule on every frame, the fastest of
// `runs` passes per frame; and a peer doing the same work the plain way, which also checks it: one sort and
// sweep of all triangle boxes on the longest axis, pairs sharing a welded corner skipped, TrianglesIntersect
// on prepared triangles, then the rule asked of the graph (CreaseScratch::Near, bounded Dijkstra) for each
// intersecting pair. Its contacts must equal the job's on every frame.
// What SkinContacts leaves for the CGAL section: its model (the crease rule's graph) and, per frame, the job's
// contacts (sorted) and fastest times, without and with the joint matrices (empty when not run).
// The folds' closing of the restricted skin contacts, × the contact margin: playback::SessionOptions'
// default (this bench links the runtime only).
constexpr float kFoldClosing = 2.0f;

struct SkinFrames {
  std::unique_ptr<sc::NarrowPhaseModel> model = std::make_unique<sc::NarrowPhaseModel>();
  std::vector<std::vector<TrianglePair>> contacts;
  std::vector<double> us, cull_us;
};

bool SkinContacts(const Workload& w, const sc::AssetView& view, int runs, bool per_frame, SkinFrames* result) {
  sc::NarrowPhaseModel& np = *result->model;
  sc::NarrowPhaseWorkspace np_ws;
  const double init_ms = Micros([&] { (void)np.Init(view); }) / 1000.0;
  if (!np.has_crease() || np_ws.Init(np) != sc::Status::kOk) {
    std::printf("\nskin contacts: skipped (the asset has no crease rule: bake it again)\n");
    return true;
  }
  const size_t F = w.frames.size();
  const uint32_t T = np.triangle_count();
  const uint32_t* tri = view.asset->triangles()->data();
  std::vector<sc::TriangleContact> out(size_t{1} << 20);
  uint32_t count = 0;
  sc::NarrowPhaseStats st;
  sc::NarrowPhaseJob job = NarrowJob(np, np_ws, sc::Exclusions::kCrease, out, &count, &st);
  std::vector<sc::NarrowPhaseStats> stats(F);
  std::vector<double> us(F, 1e300), peer_us(F, 1e300);
  std::vector<std::vector<TrianglePair>> found(F), peer(F);
  // The peer's scratch.
  std::vector<float> box(6 * size_t{T});
  std::vector<std::pair<float, uint32_t>> order;
  std::vector<sc::PreparedTriangle> prepared(T);
  std::vector<int8_t> state(T);
  sc::CreaseScratch scratch;
  (void)scratch.Init(np.crease_graph());
  auto sweep_all = [&](const float* pos, std::vector<TrianglePair>* pairs) {
    pairs->clear();
    order.clear();
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (uint32_t t = 0; t < T; ++t) {
      const uint32_t* v = tri + 3 * size_t{t};
      if (np.weld_id(v[0]) == np.weld_id(v[1]) || np.weld_id(v[1]) == np.weld_id(v[2]) || np.weld_id(v[0]) == np.weld_id(v[2]))
        continue;
      for (int k = 0; k < 3; ++k) {
        float a = pos[3 * size_t{v[0]} + k], b = pos[3 * size_t{v[1]} + k], c = pos[3 * size_t{v[2]} + k];
        box[6 * size_t{t} + k] = std::min({a, b, c});
        box[6 * size_t{t} + 3 + k] = std::max({a, b, c});
        lo[k] = std::min(lo[k], box[6 * size_t{t} + k]), hi[k] = std::max(hi[k], box[6 * size_t{t} + 3 + k]);
      }
      order.emplace_back(0.0f, t);
      state[t] = 0;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    for (auto& o : order) o.first = box[6 * size_t{o.second} + axis];
    std::sort(order.begin(), order.end());
    scratch.Reset();
    auto ready = [&](uint32_t t) {
      if (state[t] == 0) {
        const uint32_t* v = tri + 3 * size_t{t};
        state[t] = sc::PrepareTriangle(pos + 3 * size_t{v[0]}, pos + 3 * size_t{v[1]}, pos + 3 * size_t{v[2]}, &prepared[t]) ? 1 : 2;
      }
      return state[t] == 1;
    };
    for (size_t i = 0; i < order.size(); ++i) {
      const uint32_t t = order[i].second;
      const float* bt = &box[6 * size_t{t}];
      const uint32_t* tv = tri + 3 * size_t{t};
      for (size_t j = i + 1; j < order.size() && order[j].first <= bt[3 + axis]; ++j) {
        const uint32_t u = order[j].second;
        const float* bu = &box[6 * size_t{u}];
        bool overlap = true;
        for (int k = 0; k < 3; ++k) overlap &= bu[k] <= bt[3 + k] && bu[3 + k] >= bt[k];
        if (!overlap) continue;
        const uint32_t* uv = tri + 3 * size_t{u};
        bool shared = false;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) shared |= np.weld_id(tv[a]) == np.weld_id(uv[b]);
        if (shared || !ready(t) || !ready(u) || !sc::TrianglesIntersect(prepared[t], prepared[u])) continue;
        if (scratch.Near(np.crease_graph(), tv, uv, np.crease())) continue;
        pairs->emplace_back(std::min(t, u), std::max(t, u));
      }
    }
    std::sort(pairs->begin(), pairs->end());
  };
  for (size_t f = 0; f < F; ++f) {
    job.positions = {w.frames[f].data(), w.vertex_count, 12};
    if (sc::Status s = job.Run(); s != sc::Status::kOk) {
      std::fprintf(stderr, "skin contacts, frame %zu: %s\n", f, sc::ToString(s));
      return false;
    }
    stats[f] = st;
    for (uint32_t i = 0; i < count; ++i)
      found[f].emplace_back(std::min(out[i].triangle_a, out[i].triangle_b), std::max(out[i].triangle_a, out[i].triangle_b));
    std::sort(found[f].begin(), found[f].end());
  }
  // The same job given each frame's joint matrices (an asset baked with skin weights, frames with .joints):
  // the joint-matrix cull. Its contacts are checked against the job's; timed in the same passes.
  const bool cull = np.has_joint_cull() && w.joints.size() == F;
  std::vector<double> cull_us(F, 1e300);
  std::vector<sc::NarrowPhaseStats> cull_stats(F);
  bool ok = true;
  sc::NarrowPhaseJob cull_job = job;
  std::vector<sc::TriangleContact> cull_out(out.size());
  uint32_t cull_count = 0;
  sc::NarrowPhaseStats cull_st;
  cull_job.output = cull_out.data(), cull_job.count = &cull_count, cull_job.stats = &cull_st;
  cull_job.joint_count = np.joint_count();
  for (size_t f = 0; cull && f < F; ++f) {
    cull_job.positions = {w.frames[f].data(), w.vertex_count, 12};
    cull_job.joint_matrices = w.joints[f].data();
    if (sc::Status s = cull_job.Run(); s != sc::Status::kOk) {
      std::fprintf(stderr, "skin contacts with joint matrices, frame %zu: %s\n", f, sc::ToString(s));
      return false;
    }
    cull_stats[f] = cull_st;
    std::vector<TrianglePair> pairs;
    for (uint32_t i = 0; i < cull_count; ++i)
      pairs.emplace_back(std::min(cull_out[i].triangle_a, cull_out[i].triangle_b), std::max(cull_out[i].triangle_a, cull_out[i].triangle_b));
    std::sort(pairs.begin(), pairs.end());
    if (pairs != found[f]) {
      std::fprintf(stderr, "MISMATCH skin contacts with joint matrices, frame %zu: %zu, without %zu\n", f, pairs.size(), found[f].size());
      ok = false;
    }
  }
  // The restricted path, at play --narrow-behind's defaults (playback::SessionOptions): per frame RefitJob
  // (untimed), then, timed together, DetectJob M2 at 1.5 x the contact margin (one margin for every pair),
  // FoldPairs closing by kFoldClosing x it, and the crease job on the reach regions behind those pairs. Timed in the
  // same passes as the job; its contacts must be the job's (a subset), and how many it finds is printed.
  sc::Model sm;
  sc::Workspace sws;
  sc::NarrowPhaseModel rnp;
  sc::NarrowPhaseWorkspace rws;
  const bool restricted = sm.Init(view) == sc::Status::kOk && sws.Init(sm) == sc::Status::kOk &&
                          rnp.Init(view, sc::NarrowPhaseRegions::kReach) == sc::Status::kOk &&
                          rws.Init(rnp) == sc::Status::kOk && rnp.has_crease();
  std::vector<sc::Collision> rpairs(size_t{sc::DetectBound(view, sc::DetectMethod::kM2)} + rnp.fold_pair_count());
  std::vector<sc::TriangleContact> rout(out.size());
  uint32_t rcount = 0, rm2 = 0, rfolds = 0;
  sc::NarrowPhaseStats rst;
  sc::NarrowPhaseJob rjob = NarrowJob(rnp, rws, sc::Exclusions::kCrease, rout, &rcount, &rst);
  std::vector<double> r_us(F, 1e300);
  size_t r_found = 0, r_total = 0, r_pairs = 0, r_folds = 0, r_patch_pairs = 0, r_box_tests = 0, r_tests = 0;
  auto refit = [&](size_t f) {
    sc::RefitJob job_refit;
    job_refit.model = &sm;
    job_refit.workspace = &sws;
    job_refit.positions = {w.frames[f].data(), w.vertex_count, 12};
    return job_refit.Run();
  };
  auto restricted_run = [&](size_t f) {
    sc::DetectJob m2;
    m2.model = &sm;
    m2.workspace = &sws;
    m2.method = sc::DetectMethod::kM2;
    m2.margin = 1.5f * sm.contact_margin();
    if (sm.fold_margin() >= 0.0f) m2.fold_margin = m2.margin;
    m2.output = rpairs.data();
    m2.capacity = static_cast<uint32_t>(rpairs.size());
    m2.count = &rm2;
    if (sc::Status s = m2.Run(); sc::Failed(s)) return s;
    if (sc::Status s = sc::FoldPairs(rnp, sws.spheres(), kFoldClosing * sm.contact_margin(), rpairs.data() + rm2,
                                     static_cast<uint32_t>(rpairs.size()) - rm2, &rfolds);
        sc::Failed(s))
      return s;
    rjob.positions = {w.frames[f].data(), w.vertex_count, 12};
    rjob.sphere_pairs = rpairs.data();
    rjob.sphere_pair_count = rm2 + rfolds;
    return rjob.Run();
  };
  for (size_t f = 0; restricted && f < F; ++f) {
    if (sc::Status s = refit(f); sc::Failed(s) || sc::Failed(s = restricted_run(f))) {
      std::fprintf(stderr, "skin contacts behind the proxy, frame %zu: %s\n", f, sc::ToString(s));
      return false;
    }
    for (uint32_t i = 0; i < rcount; ++i) {
      const TrianglePair p{std::min(rout[i].triangle_a, rout[i].triangle_b), std::max(rout[i].triangle_a, rout[i].triangle_b)};
      if (!std::binary_search(found[f].begin(), found[f].end(), p)) {
        std::fprintf(stderr, "MISMATCH skin contacts behind the proxy, frame %zu: a contact the job did not report\n", f);
        ok = false;
      }
    }
    r_found += rcount, r_total += found[f].size(), r_pairs += rm2 + rfolds, r_folds += rfolds;
    r_patch_pairs += rst.candidate_pairs, r_box_tests += rst.box_tests, r_tests += rst.triangle_tests;
  }
  for (int k = 0; k < runs; ++k)
    for (size_t f = 0; f < F; ++f) {
      job.positions = {w.frames[f].data(), w.vertex_count, 12};
      us[f] = std::min(us[f], Micros([&] { (void)job.Run(); }));
      if (restricted) {
        (void)refit(f);
        r_us[f] = std::min(r_us[f], Micros([&] { (void)restricted_run(f); }));
      }
      if (cull) {
        cull_job.positions = job.positions;
        cull_job.joint_matrices = w.joints[f].data();
        cull_us[f] = std::min(cull_us[f], Micros([&] { (void)cull_job.Run(); }));
      }
      if (k < 2) peer_us[f] = std::min(peer_us[f], Micros([&] { sweep_all(w.frames[f].data(), &peer[f]); }));
    }
#if SPHERECHAIN_BENCH_EMBREE
  EmbreePeer embree;
  std::vector<double> embree_us(F, 1e300), embree_build_us(F, 1e300);
  uint64_t embree_box_pairs = 0;
  if (embree.Init(np, tri, T)) {
    std::vector<TrianglePair> pairs;
    for (int k = 0; k < std::min(runs, 2); ++k)
      for (size_t f = 0; f < F; ++f) {
        double build = 0;
        const double total = Micros([&] { build = embree.Frame(w.frames[f].data(), &pairs); });
        if (total < embree_us[f]) embree_us[f] = total, embree_build_us[f] = build;
        if (k == 0 && pairs != found[f]) {
          std::fprintf(stderr, "MISMATCH skin contacts, frame %zu: job %zu, Embree %zu\n", f, found[f].size(), pairs.size());
          ok = false;
        }
      }
    embree_box_pairs = embree.box_pairs / (uint64_t{F} * std::min(runs, 2));
  } else {
    std::fprintf(stderr, "Embree: rtcNewDevice failed\n");
  }
#endif
  for (size_t f = 0; f < F; ++f)
    if (peer[f] != found[f]) {
      std::fprintf(stderr, "MISMATCH skin contacts, frame %zu: job %zu, whole-mesh sweep %zu\n", f, found[f].size(), peer[f].size());
      ok = false;
    }
  const Summary time = Summarize(us), ptime = Summarize(peer_us);
  const Summary pairs = Summarize(Column(stats, &sc::NarrowPhaseStats::candidate_pairs));
  const Summary box_tests = Summarize(Column(stats, &sc::NarrowPhaseStats::box_tests));
  const Summary tests = Summarize(Column(stats, &sc::NarrowPhaseStats::triangle_tests));
  const Summary hits = Summarize(Column(stats, &sc::NarrowPhaseStats::contacts));
  std::printf("\nskin contacts (NarrowPhaseJob, Exclusions::kCrease: crease %.4g, %u bind contacts; one core)\n",
              double(np.crease()), np.bind_contact_count());
  std::printf("NarrowPhaseModel::Init %.1f ms (patches and near bits included: %u patches, %.2f MB)\n", init_ms,
              np.crease_patch_count(), double(np.crease_patch_bytes()) / 1e6);
  std::printf("%-30s %12s %12s %12s\n", "per frame", "median", "mean", "max");
  std::printf("%-30s %12.1f %12.1f %12.1f  (frame %zu)\n", "time us", time.median, time.mean, time.max, time.argmax);
  std::printf("%-30s %12.0f %12.1f %12.0f\n", "patch pairs looked at", pairs.median, pairs.mean, pairs.max);
  std::printf("%-30s %12.0f %12.1f %12.0f\n", "triangle box tests", box_tests.median, box_tests.mean, box_tests.max);
  std::printf("%-30s %12.0f %12.1f %12.0f\n", "exact triangle tests", tests.median, tests.mean, tests.max);
  std::printf("%-30s %12.0f %12.1f %12.0f\n", "contacts", hits.median, hits.mean, hits.max);
  if (cull) {
    const Summary ctime = Summarize(cull_us);
    const Summary culled = Summarize(Column(cull_stats, &sc::NarrowPhaseStats::joint_culled));
    const Summary cbox = Summarize(Column(cull_stats, &sc::NarrowPhaseStats::box_tests));
    std::printf("%-30s %12.1f %12.1f %12.1f  (frame %zu)\n", "with joint matrices: us", ctime.median, ctime.mean,
                ctime.max, ctime.argmax);
    std::printf("%-30s %12.0f %12.1f %12.0f\n", "  patch pairs culled", culled.median, culled.mean, culled.max);
    std::printf("%-30s %12.0f %12.1f %12.0f\n", "  triangle box tests", cbox.median, cbox.mean, cbox.max);
    std::printf("ratio job / job with joint matrices: %.2fx (medians), %.2fx (maxima); contacts equal: %s\n",
                time.median / ctime.median, time.max / ctime.max, ok ? "yes" : "NO");
  } else {
    std::printf("with joint matrices: not run (%s)\n",
                np.has_joint_cull() ? "the frames have no .joints" : "the asset has no skin weights: bake --skin-weights");
  }
  if (restricted) {
    const Summary rtime = Summarize(r_us);
    std::printf("%-30s %12.1f %12.1f %12.1f  (frame %zu; M2 at 1.5 x the margin + folds at %g x, %.1f pairs a frame, "
                "%.1f of them folds; reach regions)\n",
                "behind the proxy: us", rtime.median, rtime.mean, rtime.max, rtime.argmax, double(kFoldClosing),
                F ? double(r_pairs) / F : 0.0,
                F ? double(r_folds) / F : 0.0);
    std::printf("ratio job / behind the proxy: %.2fx (medians), %.2fx (maxima); contacts found %zu of %zu (%.2f %%); "
                "%.1f patch pairs looked at, %.0f triangle box tests and %.1f exact tests a frame (means)\n",
                time.median / rtime.median, time.max / rtime.max, r_found, r_total,
                r_total ? 100.0 * double(r_found) / double(r_total) : 100.0, F ? double(r_patch_pairs) / F : 0.0,
                F ? double(r_box_tests) / F : 0.0, F ? double(r_tests) / F : 0.0);
  }
  std::printf("%-30s %12.1f %12.1f %12.1f  (best of %d)\n", "peer: whole-mesh sweep us", ptime.median, ptime.mean,
              ptime.max, std::min(runs, 2));
  std::printf("ratio whole-mesh sweep / job: %.1fx (medians), %.1fx (maxima); contacts equal on every frame: %s\n",
              ptime.median / time.median, ptime.max / time.max, ok ? "yes" : "NO");
#if SPHERECHAIN_BENCH_EMBREE
  const Summary etime = Summarize(embree_us), ebuild = Summarize(embree_build_us);
  std::printf("%-30s %12.1f %12.1f %12.1f  (best of %d; refit/build median %.1f us; %llu box pairs a frame)\n",
              "peer: Embree rtcCollide us", etime.median, etime.mean, etime.max, std::min(runs, 2), ebuild.median,
              static_cast<unsigned long long>(embree_box_pairs));
  std::printf("ratio Embree / job: %.1fx (medians), %.1fx (maxima)\n", etime.median / time.median, etime.max / time.max);
#else
  std::printf("Embree peer: not built (libembree-dev not found at configure time)\n");
#endif
  if (per_frame) {
    std::printf("%5s %9s %9s %10s %11s %11s %7s %8s\n", "frame", "us", "cull us", "patch pairs", "box tests",
                "cull boxes", "exact", "contacts");
    for (size_t f = 0; f < F; ++f) {  // "-" in the cull columns when the cull did not run (reason above)
      char cull_time[16] = "-", cull_boxes[16] = "-";
      if (cull) {
        std::snprintf(cull_time, sizeof cull_time, "%.1f", cull_us[f]);
        std::snprintf(cull_boxes, sizeof cull_boxes, "%u", cull_stats[f].box_tests);
      }
      std::printf("%5zu %9.1f %9s %10u %11u %11s %7u %8u\n", f, us[f], cull_time, stats[f].candidate_pairs,
                  stats[f].box_tests, cull_boxes, stats[f].triangle_tests, stats[f].contacts);
    }
  }
  result->contacts = std::move(found);
  result->us = std::move(us);
  if (cull) result->cull_us = std::move(cull_us);
  return ok;
}

#if SPHERECHAIN_BENCH_CGAL
// The crease rule's geodesics (crease.h: Dijkstra on the welded edge graph) against exact ones (CGAL
// Surface_mesh_shortest_path, Xin–Wang's variant of Chen–Han) on the asset's bind pose: from `sources`
// vertices spread over the mesh, every vertex within twice the crease (exact) compared. Prints the ratio
// Dijkstra / exact and how many pairs nearer than the crease the graph puts beyond it.
bool Geodesics(const sc::AssetView& view, uint32_t sources) {
  sc::NarrowPhaseModel np;
  if (np.Init(view) != sc::Status::kOk || !np.has_crease()) {
    std::printf("geodesics: the asset has no crease rule (bake it again)\n");
    return false;
  }
  const NarrowAsset m{&np, view.asset->triangles()->data(), np.triangle_count()};
  CgalPeer peer;
  if (const std::string why = peer.Build(m, view.vertex_count); !why.empty()) {
    std::printf("geodesics: %s\n", why.c_str());
    return false;
  }
  peer.SetFrame(view.asset->bind_positions()->data());
  using Traits = CGAL::Surface_mesh_shortest_path_traits<Epick, CgalMesh>;
  using Shortest = CGAL::Surface_mesh_shortest_path<Traits>;
  const double crease = np.crease();
  const uint32_t V = static_cast<uint32_t>(peer.mesh.number_of_vertices());
  std::vector<double> ratio;
  size_t near = 0, near_called_apart = 0;
  double worst_missed = 1;  // the smallest exact distance / crease among pairs the graph calls apart
  double build_ms = 0;
  std::vector<double> dist(V);
  std::vector<std::pair<double, uint32_t>> heap;
  std::vector<CgalMesh::Vertex_index> used;  // vertices with a face (the welded ones' representatives)
  for (CgalMesh::Vertex_index v : peer.mesh.vertices())
    if (!peer.mesh.is_isolated(v)) used.push_back(v);
  for (uint32_t k = 0; k < sources; ++k) {
    const CgalMesh::Vertex_index src = used[(uint64_t{k} * used.size()) / sources];
    Shortest shortest(peer.mesh);
    build_ms += Micros([&] {
      shortest.add_source_point(src);
      shortest.build_sequence_tree();
    }) / 1000.0;
    // Dijkstra on the same mesh's edges, bind lengths: the crease rule's graph.
    std::fill(dist.begin(), dist.end(), std::numeric_limits<double>::infinity());
    dist[src.idx()] = 0;
    heap.assign(1, {0.0, src.idx()});
    while (!heap.empty()) {
      std::pop_heap(heap.begin(), heap.end(), std::greater<>());
      const auto [d, v] = heap.back();
      heap.pop_back();
      if (d > dist[v] || d > 4 * crease) continue;
      for (CgalMesh::Halfedge_index h : CGAL::halfedges_around_source(CgalMesh::Vertex_index(v), peer.mesh)) {
        const CgalMesh::Vertex_index u = peer.mesh.target(h);
        const double nd = d + std::sqrt(CGAL::to_double(CGAL::squared_distance(peer.mesh.point(CgalMesh::Vertex_index(v)), peer.mesh.point(u))));
        if (nd < dist[u.idx()]) {
          dist[u.idx()] = nd;
          heap.emplace_back(nd, u.idx());
          std::push_heap(heap.begin(), heap.end(), std::greater<>());
        }
      }
    }
    for (CgalMesh::Vertex_index v : used) {
      if (v == src || !(dist[v.idx()] <= 4 * crease)) continue;  // ratios above 2 not seen (none were)
      const double exact = shortest.shortest_distance_to_source_points(v).first;
      if (!(exact > 0) || exact > 2 * crease) continue;
      ratio.push_back(dist[v.idx()] / exact);
      if (exact < crease) {
        ++near;
        if (dist[v.idx()] >= crease) ++near_called_apart, worst_missed = std::min(worst_missed, exact / crease);
      }
    }
  }
  if (ratio.empty()) {
    std::printf("geodesics: no vertex pair within twice the crease\n");
    return false;
  }
  std::sort(ratio.begin(), ratio.end());
  auto q = [&](double f) { return ratio[std::min(ratio.size() - 1, size_t(f * double(ratio.size())))]; };
  std::printf("\ngeodesics: Dijkstra on the welded edge graph / exact (CGAL Surface_mesh_shortest_path), bind pose, "
              "%u sources, %zu vertex pairs within 2 x the crease (%.4g; the graph searched to 4 x)\n", sources, ratio.size(), crease);
  std::printf("ratio: min %.4f, median %.4f, p90 %.4f, p99 %.4f, max %.4f\n", ratio.front(), q(0.5), q(0.9), q(0.99),
              ratio.back());
  std::printf("pairs nearer than the crease: %zu, of which the graph puts %zu (%.2f %%) at or beyond it (the nearest "
              "of those at %.3f x the crease)\n", near, near_called_apart, 100.0 * double(near_called_apart) / double(std::max<size_t>(near, 1)),
              near_called_apart ? worst_missed : 0.0);
  std::printf("CGAL sequence tree: %.0f ms a source (one core)\n", build_ms / sources);
  return true;
}
#endif

bool NarrowPhase(const Workload& w, const sc::AssetView& view, int runs, int cgal_frames, bool per_frame,
                 const std::vector<float>& margin_scales) {
  sc::NarrowPhaseModel np;
  sc::NarrowPhaseWorkspace np_ws;
  if (sc::Status s = np.Init(view); s != sc::Status::kOk || (s = np_ws.Init(np)) != sc::Status::kOk) {
    std::printf("\nnarrow phase: skipped (NarrowPhaseModel / NarrowPhaseWorkspace::Init: %s%s)\n", sc::ToString(s),
                s == sc::Status::kErrorMissingField ? "; the asset has no triangles / weld_ids: re-bake it" : "");
    return true;
  }
  const NarrowAsset m{&np, view.asset->triangles()->data(), np.triangle_count()};
  const size_t F = w.frames.size();
  const double T = np.triangle_count(), all_pairs = T * (T - 1) / 2;
  std::vector<sc::TriangleContact> out(size_t{1} << 20);
  uint32_t count = 0;
  sc::NarrowPhaseStats st;
  sc::NarrowPhaseJob job = NarrowJob(np, np_ws, sc::Exclusions::kAsset, out, &count, &st);
  // Region boxes alone: an explicit, empty list of candidate sphere pairs.
  const sc::Collision no_pair{};
  sc::NarrowPhaseJob boxes_only = job;
  boxes_only.sphere_pairs = &no_pair;
  boxes_only.sphere_pair_count = 0;
  auto set_frame = [&](size_t f) {
    job.positions = boxes_only.positions = {w.frames[f].data(), w.vertex_count, 12};
  };

  // Untimed pass: statistics and contact sets.
  bool ok = true;
  std::vector<sc::NarrowPhaseStats> stats(F);
  std::vector<std::vector<TrianglePair>> contacts(F);
  for (size_t f = 0; f < F; ++f) {
    set_frame(f);
    if (sc::Status s = job.Run(); s != sc::Status::kOk) {
      std::fprintf(stderr, "narrow phase, frame %zu: %s\n", f, sc::ToString(s));
      return false;
    }
    stats[f] = st;
    for (uint32_t i = 0; i < count; ++i)
      contacts[f].emplace_back(std::min(out[i].triangle_a, out[i].triangle_b),
                               std::max(out[i].triangle_a, out[i].triangle_b));
    std::sort(contacts[f].begin(), contacts[f].end());
  }
  // Timed: `runs` passes over the frames in turn (caches as warm as a game's, not warmer); per frame
  // the fastest pass. Same for the region boxes alone.
  std::vector<double> us(F, 1e300), boxes_us(F, 1e300);
  for (int k = 0; k < runs; ++k)
    for (size_t f = 0; f < F; ++f) {
      set_frame(f);
      us[f] = std::min(us[f], Micros([&] { (void)job.Run(); }));
      g_sink = g_sink + count;
      boxes_us[f] = std::min(boxes_us[f], Micros([&] { (void)boxes_only.Run(); }));
    }
  // Replica of the tested pairs: checks stats.triangle_tests and times the exact tests alone, as the
  // narrow phase runs them: each triangle of a tested pair prepared once, then the prepared test.
  std::vector<double> exact_us(F, 1e300);
  std::vector<sc::PreparedTriangle> prepared(np.triangle_count());
  for (size_t f = 0; f < F; ++f) {
    const float* p = w.frames[f].data();
    const std::vector<TrianglePair> pairs = TestedPairs(m, p);
    std::vector<uint32_t> tested;
    for (const auto& [s, t] : pairs) tested.push_back(s), tested.push_back(t);
    std::sort(tested.begin(), tested.end());
    tested.erase(std::unique(tested.begin(), tested.end()), tested.end());
    uint32_t hits = 0;
    for (int k = 0; k < runs; ++k)
      exact_us[f] = std::min(exact_us[f], Micros([&] {
                               for (const uint32_t t : tested)
                                 (void)sc::PrepareTriangle(m.Corner(p, t, 0), m.Corner(p, t, 1), m.Corner(p, t, 2),
                                                           &prepared[t]);
                               hits = 0;
                               for (const auto& [s, t] : pairs) hits += sc::TrianglesIntersect(prepared[s], prepared[t]);
                             }));
    if (pairs.size() != stats[f].triangle_tests || hits != stats[f].contacts) {
      std::fprintf(stderr, "MISMATCH narrow phase, frame %zu: %u tests, %u contacts; replica %zu pairs, %u intersect\n",
                   f, stats[f].triangle_tests, stats[f].contacts, pairs.size(), hits);
      ok = false;
    }
  }

  const Summary time = Summarize(us), boxes = Summarize(boxes_us), exact = Summarize(exact_us);
  const Summary cand = Summarize(Column(stats, &sc::NarrowPhaseStats::candidate_pairs));
  const Summary tests = Summarize(Column(stats, &sc::NarrowPhaseStats::triangle_tests));
  const Summary hits = Summarize(Column(stats, &sc::NarrowPhaseStats::contacts));
  const Summary box_tests = Summarize(Column(stats, &sc::NarrowPhaseStats::box_tests));
  const Summary culled = Summarize(Column(stats, &sc::NarrowPhaseStats::culled_triangles));
  const Summary adjacent = Summarize(Column(stats, &sc::NarrowPhaseStats::adjacent_skipped));
  const Summary degenerate = Summarize(Column(stats, &sc::NarrowPhaseStats::degenerate_triangles));
  std::vector<double> rest_us(F);
  for (size_t f = 0; f < F; ++f) rest_us[f] = std::max(0.0, us[f] - boxes_us[f] - exact_us[f]);
  const Summary rest = Summarize(rest_us);

  std::printf("\nnarrow phase (NarrowPhaseJob, asset exclusions, capacity %u contacts, one core)\n", job.capacity);
  std::printf("triangles %.0f (all pairs %.4g), %u spheres, %u index-degenerate, %u in no surrounding region; "
              "%zu frames, each the fastest of %d pass%s over the frames in turn\n",
              T, all_pairs, np.sphere_count(), np.index_degenerate_triangles(), np.unassigned_triangles(), F, runs,
              runs > 1 ? "es" : "");
  std::printf("%-26s %12s %12s %12s\n", "per frame", "median", "mean", "max");
  std::printf("%-26s %12.1f %12.1f %12.1f  (frame %zu)\n", "time us", time.median, time.mean, time.max, time.argmax);
  std::printf("%-26s %12.0f %12.1f %12.0f\n", "candidate sphere pairs", cand.median, cand.mean, cand.max);
  std::printf("%-26s %12.0f %12.1f %12.0f\n", "exact triangle tests", tests.median, tests.mean, tests.max);
  std::printf("%-26s %12.0f %12.1f %12.0f\n", "contacts", hits.median, hits.mean, hits.max);
  std::printf("%-26s %12.0f %12.1f %12.0f\n", "triangle box tests", box_tests.median, box_tests.mean, box_tests.max);
  std::printf("%-26s %12.0f %12.1f %12.0f\n", "culled-in triangles", culled.median, culled.mean, culled.max);
  std::printf("%-26s %12.0f %12.1f %12.0f\n", "adjacent pairs skipped", adjacent.median, adjacent.mean, adjacent.max);
  std::printf("%-26s %12.0f %12.1f %12.0f\n", "degenerate triangles", degenerate.median, degenerate.mean,
              degenerate.max);
  std::printf("all pairs / exact tests: %.0fx at the mean, %.0fx on the worst frame (target >= 1000x)\n",
              all_pairs / std::max(1.0, tests.mean), all_pairs / std::max(1.0, tests.max));
  std::printf("breakdown us (median / max over frames): region boxes %.1f / %.1f (Run on an empty pair list); "
              "exact tests %.1f / %.1f (alone on the same pairs: each triangle prepared, then the prepared test; %.0f ns a test); "
              "rest %.1f / %.1f (candidates, triangle boxes, culling, box tests)\n",
              boxes.median, boxes.max, exact.median, exact.max,
              1000.0 * std::accumulate(exact_us.begin(), exact_us.end(), 0.0) /
                  std::max(1.0, tests.mean * double(F)),
              rest.median, rest.max);
  std::vector<size_t> slow(F);
  std::iota(slow.begin(), slow.end(), size_t{0});
  std::sort(slow.begin(), slow.end(), [&](size_t a, size_t b) { return us[a] > us[b]; });
  std::printf("slowest frames:");
  for (size_t i = 0; i < std::min<size_t>(3, F); ++i) {
    const size_t f = slow[i];
    std::printf("%s %zu (%.1f us: boxes %.1f, tests %.1f, rest %.1f; %u candidates, %u box tests, %u tests, %u contacts)",
                i ? ";" : "", f, us[f], boxes_us[f], exact_us[f], rest_us[f], stats[f].candidate_pairs,
                stats[f].box_tests, stats[f].triangle_tests, stats[f].contacts);
  }
  std::printf("\n");
  if (per_frame) {
    std::printf("%5s %9s %7s %7s %7s %10s %11s %7s %8s\n", "frame", "us", "boxes", "tests", "rest", "candidates",
                "box tests", "exact", "contacts");
    for (size_t f = 0; f < F; ++f)
      std::printf("%5zu %9.1f %7.1f %7.1f %7.1f %10u %11u %7u %8u\n", f, us[f], boxes_us[f], exact_us[f], rest_us[f],
                  stats[f].candidate_pairs, stats[f].box_tests, stats[f].triangle_tests, stats[f].contacts);
  }
  std::printf("replica (bench-side sweep over all triangle boxes): tested pairs and contacts %s on every frame\n",
              ok ? "equal" : "DIFFER (see stderr)");
  for (float scale : margin_scales) ok = BehindTheProxy(w, view, runs, contacts, scale) && ok;
  SkinFrames skin;
  ok = SkinContacts(w, view, runs, per_frame, &skin) && ok;

#if SPHERECHAIN_BENCH_CGAL
  const size_t G = std::min(F, size_t(std::max(0, cgal_frames)));
  if (G == 0) return ok;
  CgalPeer peer;
  std::string why;
  try {
    why = peer.Build(m, w.vertex_count);
  } catch (const std::exception& e) {
    why = e.what();
  }
  if (!why.empty()) {
    std::printf("CGAL self_intersections: skipped (%s)\n", why.c_str());
    return ok;
  }
  std::printf("\nCGAL PMP::self_intersections (Epick, Sequential_tag, Surface_mesh over welded vertices, %zu faces; "
              "orient_polygon_soup %s, %zu points duplicated), first %zu of %zu frames, 1 run each "
              "(points set before the clock)\n",
              size_t{peer.mesh.number_of_faces()}, peer.oriented ? "ok" : "false", peer.duplicated_points, G, F);
  std::printf("%5s %9s %9s %8s %9s %11s | CGAL pairs: %6s %9s %8s %8s %7s %6s  %s\n", "frame", "sc us", "CGAL ms",
              "CGAL/sc", "contacts", "CGAL pairs", "degen.", "no region", "1 region", "excluded", "welded", "ours",
              "ours = contacts");
  std::vector<double> cgal_ms, sc_us, skin_us, skin_cull_us;
  std::vector<std::pair<CgalMesh::Face_index, CgalMesh::Face_index>> pairs;
  size_t agree = 0, skin_agree = 0;
  // The skin's definition from CGAL's pairs: two faces with no welded corner in common (degenerate ones
  // reported as (f, f) left out) that the crease rule does not call near.
  const sc::NarrowPhaseModel& skin_np = *skin.model;
  const bool skin_run = skin_np.has_crease() && skin.contacts.size() == F;
  sc::CreaseScratch skin_scratch;
  if (skin_run) (void)skin_scratch.Init(skin_np.crease_graph());
  auto skin_pairs = [&]() {
    std::vector<TrianglePair> out;
    skin_scratch.Reset();
    for (const auto& [f, g] : pairs) {
      if (f == g) continue;
      const uint32_t s = peer.face_source[f.idx()], t = peer.face_source[g.idx()];
      if (m.Adjacent(s, t)) continue;
      if (skin_scratch.Near(skin_np.crease_graph(), m.triangles + 3 * size_t{s}, m.triangles + 3 * size_t{t}, skin_np.crease()))
        continue;
      out.emplace_back(std::min(s, t), std::max(s, t));
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  for (size_t f = 0; f < G; ++f) {
    peer.SetFrame(w.frames[f].data());
    pairs.clear();
    double t_us = 0;
    try {
      t_us = Micros([&] { PMP::self_intersections<CGAL::Sequential_tag>(faces(peer.mesh), peer.mesh, std::back_inserter(pairs)); });
    } catch (const std::exception& e) {
      std::printf("%5zu CGAL threw: %s\n", f, e.what());
      continue;
    }
    const CgalClasses c = Classify(m, peer, pairs);
    const bool same = c.ours == contacts[f];
    agree += same;
    cgal_ms.push_back(t_us / 1000.0);
    sc_us.push_back(us[f]);
    if (skin_run) {
      skin_agree += skin_pairs() == skin.contacts[f];
      skin_us.push_back(skin.us[f]);
      if (!skin.cull_us.empty()) skin_cull_us.push_back(skin.cull_us[f]);
    }
    std::printf("%5zu %9.1f %9.1f %7.0fx %9zu %11zu | %18zu %9zu %8zu %8zu %7zu %6zu  %s\n", f, us[f], t_us / 1000.0,
                t_us / us[f], contacts[f].size(), c.all, c.degenerate, c.unassigned, c.same_region, c.excluded,
                c.weld_adjacent, c.ours.size(), same ? "yes" : "NO");
  }
  const Summary cg = Summarize(cgal_ms), ours = Summarize(sc_us);
  std::printf("CGAL ms per frame: median %.1f, max %.1f (frame %zu); narrow phase on the same frames: median %.1f us, "
              "max %.1f us\n",
              cg.median, cg.max, cg.argmax, ours.median, ours.max);
  std::printf("ratio CGAL / narrow phase: %.0fx (medians), %.0fx (maxima)\n", 1000.0 * cg.median / ours.median,
              1000.0 * cg.max / ours.max);
  std::printf("CGAL pairs = every self-intersection (degenerate faces as (f, f), pairs in one surrounding region, in "
              "excluded sphere pairs, with a triangle in no region, across a welded corner CGAL sees as two "
              "vertices); \"ours\" = the rest, our contact definition: equal to the narrow phase's contacts on %zu of "
              "%zu frames\n",
              agree, cgal_ms.size());
  if (agree != cgal_ms.size())
    std::fprintf(stderr, "note: on %zu frame(s) CGAL's pairs under our contact definition differ from the narrow "
                         "phase's contacts (rows marked NO)\n", cgal_ms.size() - agree);
  if (skin_run && !cgal_ms.empty()) {
    const Summary sk = Summarize(skin_us);
    std::printf("skin contacts (Exclusions::kCrease) on the same frames: median %.1f us, max %.1f us; ratio CGAL / "
                "job: %.0fx (medians), %.0fx (maxima)",
                sk.median, sk.max, 1000.0 * cg.median / sk.median, 1000.0 * cg.max / sk.max);
    if (!skin_cull_us.empty()) {
      const Summary kc = Summarize(skin_cull_us);
      std::printf("; with joint matrices %.1f / %.1f us, %.0fx / %.0fx", kc.median, kc.max,
                  1000.0 * cg.median / kc.median, 1000.0 * cg.max / kc.max);
    }
    std::printf("\nCGAL's pairs under the skin's definition (no welded corner in common, not near by the crease "
                "rule): equal to the job's contacts on %zu of %zu frames\n",
                skin_agree, cgal_ms.size());
    if (skin_agree != cgal_ms.size()) {
      std::fprintf(stderr, "MISMATCH: on %zu frame(s) CGAL's pairs under the skin's definition differ from the "
                           "skin-contact job's\n", cgal_ms.size() - skin_agree);
      ok = false;
    }
  }
#else
  (void)cgal_frames;
  std::printf("CGAL self_intersections: not built (libcgal-dev not found at configure time)\n");
#endif
  return ok;
}


// ---------------------------------------------------------------------------------------------------
// Many characters per frame: BatchJob over N workspaces sharing one Model, character c of batch b on
// frame (c + b) mod #F (each its own pose), refit from its vertex buffer (and from its joint matrices when
// the frames carry them) + M1, serial, then through the ParallelFor hook with TBB limited to 1 and 2
// threads (tbb::global_control). Characters/s = N / (median time of a batch); best median of the runs.

#if SPHERECHAIN_BENCH_TBB
// The ParallelFor hook on TBB: one tbb::parallel_for over the task indices (auto partitioner).
void TbbParallelFor(void*, uint32_t count, sc::ParallelFor::Task task, void* data) {
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, count),
                    [&](const tbb::blocked_range<uint32_t>& r) { task(data, r.begin(), r.end()); });
}
#endif

bool ManyCharacters(const Workload& w, const sc::Model& model, uint32_t n, int runs) {
  const size_t F = w.frames.size();
  std::vector<sc::Workspace> ws(n);
  for (sc::Workspace& x : ws)
    if (x.Init(model) != sc::Status::kOk) return std::fprintf(stderr, "Workspace::Init failed\n"), false;
  constexpr uint32_t kCapacity = 1024;  // records per character (MakeHuman: ~30 pairs a frame)
  std::vector<sc::Collision> out(size_t{n} * kCapacity);
  std::vector<uint32_t> count(n);
  std::vector<sc::CharacterFrame> chars(n);
  for (uint32_t c = 0; c < n; ++c) {
    chars[c].workspace = &ws[c];
    chars[c].output = out.data() + size_t{c} * kCapacity;
    chars[c].capacity = kCapacity;
    chars[c].count = &count[c];
  }
  sc::BatchJob batch;
  batch.model = &model;
  batch.characters = chars.data();
  batch.character_count = n;
  batch.method = sc::DetectMethod::kM1;
  batch.joint_count = model.joint_count();
  const bool joints = w.joints.size() == F && model.joint_count() != 0;
  auto set_frames = [&](size_t b) {
    for (uint32_t c = 0; c < n; ++c) {
      const size_t f = (c + b) % F;
      chars[c].positions = {w.frames[f].data(), w.vertex_count, 12};
      if (joints) chars[c].joint_matrices = w.joints[f].data();
    }
  };
  // Reference: every character's records and counts from the serial batch, checked in every run below.
  std::vector<uint64_t> want(F);
  auto digest = [&] {
    uint64_t h = 1469598103934665603ull;
    for (uint32_t c = 0; c < n; ++c) {
      h = (h ^ count[c]) * 1099511628211ull;
      for (uint32_t k = 0; k < count[c]; ++k) {
        const sc::Collision& x = out[size_t{c} * kCapacity + k];
        h = (h ^ (uint64_t{x.a} << 16 | x.b)) * 1099511628211ull;
      }
    }
    return h;
  };
  bool ok = true;
  batch.source = sc::RefitSource::kVertices;
  for (size_t b = 0; b < F; ++b) set_frames(b), ok = ok && batch.Run() == sc::Status::kOk, want[b] = digest();
  // Median of the batch times over the #F frame offsets (each batch timed alone: one frame of N characters).
  auto median_batch_us = [&]() {
    std::vector<double> us;
    for (size_t b = 0; b < F; ++b) {
      set_frames(b);
      const auto t0 = Clock::now();
      if (batch.Run() != sc::Status::kOk) ok = false;
      us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
      if (batch.source == sc::RefitSource::kVertices && digest() != want[b]) ok = false;
    }
    std::nth_element(us.begin(), us.begin() + us.size() / 2, us.end());
    return us[us.size() / 2];
  };
  struct Line {
    std::string name;
    double us;
  };
  std::vector<Line> lines;
  auto measure = [&](const std::string& name) {
    double best = 1e300;
    for (int k = 0; k < runs; ++k) best = std::min(best, median_batch_us());
    lines.push_back({name, best});
    return best;
  };
  double one = 0, two = 0;
  for (sc::RefitSource source : {sc::RefitSource::kVertices, sc::RefitSource::kJoints}) {
    if (source == sc::RefitSource::kJoints && !joints) continue;
    batch.source = source;
    const std::string src = source == sc::RefitSource::kVertices ? "vertices" : "joints";
    batch.parallel_for = {};
    measure("serial (no hook), refit " + src + " + M1");
#if SPHERECHAIN_BENCH_TBB
    batch.parallel_for.run = &TbbParallelFor;
    batch.parallel_grain = 4;
    for (int threads : {1, 2}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
      const double us = measure("TBB " + std::to_string(threads) + " thread" + (threads > 1 ? "s" : "") + ", refit " + src + " + M1");
      if (source == sc::RefitSource::kVertices) (threads == 1 ? one : two) = us;
    }
#endif
  }
  std::printf("\nmany characters per frame (BatchJob, %u characters sharing one Model, character c of batch b on frame "
              "(c + b) mod %zu; median batch over the %zu offsets%s)\n",
              n, F, F, runs > 1 ? ", best of the runs" : "");
  std::printf("%-44s %12s %12s %14s\n", "", "us / batch", "us / char.", "characters/s");
  for (const Line& l : lines)
    std::printf("%-44s %12.1f %12.3f %14.0f\n", l.name.c_str(), l.us, l.us / n, 1e6 * n / l.us);
#if SPHERECHAIN_BENCH_TBB
  std::printf("scaling, TBB 2 threads / 1 thread (refit vertices + M1): %.2fx (hardware threads: %u)\n", one / two,
              std::thread::hardware_concurrency());
#else
  std::printf("TBB not found at configure time (Debian: libtbb-dev): only the serial batch was timed\n");
#endif
  if (!ok) std::fprintf(stderr, "MISMATCH: a batch failed or its records differ from the serial batch's\n");
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  bool synthetic = false, narrow_only = false, per_frame = false, batch_only = false;
  uint32_t geodesics = 0;
  int reps = 200, runs = 1, profile = 0, cgal_frames = 10;
  uint32_t characters = 1000;
  uint32_t frame_count = 40;
  std::vector<float> margin_scales = {1.0f};  // --behind-margins: the "behind M2's pairs" rows' DetectJob margins
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--synthetic") synthetic = true;
    else if (a == "--reps" && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
    else if (a == "--frames" && i + 1 < argc) frame_count = std::max(1, std::atoi(argv[++i]));
    else if (a == "--runs" && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--profile" && i + 1 < argc) profile = std::max(1, std::atoi(argv[++i]));
    else if (a == "--narrow-only") narrow_only = true;
    else if (a == "--geodesics" && i + 1 < argc) geodesics = static_cast<uint32_t>(std::atoi(argv[++i]));
    else if (a == "--batch-only") batch_only = true;
    else if (a == "--characters" && i + 1 < argc) characters = uint32_t(std::max(1, std::atoi(argv[++i])));
    else if (a == "--per-frame") per_frame = true;
    else if (a == "--behind-margins" && i + 1 < argc) {
      margin_scales.clear();
      for (std::string v = argv[++i]; !v.empty();) {
        const size_t comma = v.find(',');
        char* end = nullptr;
        const std::string item = v.substr(0, comma);
        const float x = std::strtof(item.c_str(), &end);
        if (item.empty() || *end || !(x >= 0.0f && x <= 100.0f))
          return std::fprintf(stderr, "--behind-margins: '%s' is not a multiple of the asset's margin in [0, 100]\n",
                              item.c_str()), 2;
        margin_scales.push_back(x);
        v = comma == std::string::npos ? "" : v.substr(comma + 1);
      }
    }
    else if (a == "--cgal-frames" && i + 1 < argc) cgal_frames = std::max(0, std::atoi(argv[++i]));
    else positional.push_back(a);
  }
  Workload w;
  if (synthetic) {
    w = Synthetic(frame_count);
  } else if (positional.size() == 2) {
    if (!FromFiles(positional[0], positional[1], &w)) return 1;
  } else {
    std::fprintf(stderr, "usage: runtime_bench --synthetic [--frames N] [--reps R] [--runs K] [--narrow-only] "
                         "[--cgal-frames N] [--per-frame]\n"
                         "       runtime_bench ASSET.sphc FRAMES(.f32 file | folder) [--reps R] [--runs K] "
                         "[--narrow-only] [--cgal-frames N] [--per-frame] [--behind-margins S,S,...]\n"
                         "       runtime_bench ASSET.sphc FRAMES --profile R\n"
                         "       runtime_bench ASSET.sphc FRAMES --batch-only [--characters N] [--runs K]\n");
    return 2;
  }

  sc::AssetView view;
  if (sc::Status s = sc::LoadAsset(w.bytes.data(), w.bytes.size, &view); s != sc::Status::kOk)
    return std::fprintf(stderr, "load: %s\n", sc::ToString(s)), 1;
  if (geodesics) {
#if SPHERECHAIN_BENCH_CGAL
    return Geodesics(view, geodesics) ? 0 : 1;
#else
    return std::fprintf(stderr, "--geodesics needs CGAL (libcgal-dev) at configure time\n"), 2;
#endif
  }
  sc::Model model;  // shared by every character of the asset
  sc::Workspace ws;  // one character
  if (sc::Status s = model.Init(view); s != sc::Status::kOk || (s = ws.Init(model)) != sc::Status::kOk)
    return std::fprintf(stderr, "init: %s\n", sc::ToString(s)), 1;
  const uint32_t S = view.sphere_count;
  uint32_t chain_total = 0;
  for (const auto* c : *view.asset->chains()) chain_total += c->spheres()->size();
  std::printf("asset: %u spheres, %u chains (avg %.1f spheres), %u vertices, %zu frames, %d reps, contact margin %g\n",
              S, view.chain_count, view.chain_count ? double(chain_total) / view.chain_count : 0.0, view.vertex_count,
              w.frames.size(), reps, double(model.contact_margin()));

  std::vector<sc::Collision> out(std::max(sc::DetectBound(view, sc::DetectMethod::kM1),
                                          sc::DetectBound(view, sc::DetectMethod::kM2)));
  uint32_t count = 0;
  sc::RefitJob refit;
  refit.model = &model;
  refit.workspace = &ws;
  sc::DetectJob m1;
  m1.model = &model;
  m1.workspace = &ws;
  m1.method = sc::DetectMethod::kM1;
  m1.output = out.data();
  m1.capacity = static_cast<uint32_t>(out.size());
  m1.count = &count;
  sc::DetectJob m2 = m1;
  m2.method = sc::DetectMethod::kM2;
  // The peers and the naive loops test every pair on one margin (the asset's contact margin), so the compared jobs
  // do too; an asset's fold margin (pairs of one region on a smaller one) is timed in rows of its own below.
  const bool has_fold = model.fold_margin() >= 0.0f;
  if (has_fold) m1.fold_margin = m2.fold_margin = model.contact_margin();
  auto set_frame = [&](size_t f) { refit.positions = {w.frames[f].data(), w.vertex_count, 12}; };
  if (profile) {  // callgrind: Ir(RefitJob::Run + DetectJob::Run) / (profile × #F) = instructions per frame
    for (int r = 0; r < profile; ++r)
      for (size_t f = 0; f < w.frames.size(); ++f) {
        set_frame(f);
        (void)refit.Run();
        (void)m1.Run();
        g_sink = g_sink + count;
      }
    std::printf("profile: %d × %zu frames of refit + M1\n", profile, w.frames.size());
    return 0;
  }
  if (narrow_only) return NarrowPhase(w, view, runs, cgal_frames, per_frame, margin_scales) ? 0 : 1;
  if (batch_only) return ManyCharacters(w, model, characters, runs) ? 0 : 1;

  // Refitted spheres per frame (inputs of the peers) and the reference M2 counts.
  std::vector<std::vector<float>> sx(w.frames.size()), sy = sx, sz = sx, sr = sx;
  std::vector<uint32_t> m2_count(w.frames.size()), m1_count(w.frames.size());
  uint64_t broad[2][2] = {};  // [M1, M2] × [box tests, sphere tests] over the frames
  for (size_t f = 0; f < w.frames.size(); ++f) {
    set_frame(f);
    if (refit.Run() != sc::Status::kOk) return 1;
    const sc::SphereArrays s = ws.spheres();
    sx[f].assign(s.x, s.x + S), sy[f].assign(s.y, s.y + S), sz[f].assign(s.z, s.z + S), sr[f].assign(s.r, s.r + S);
    sc::DetectStats st;
    m2.stats = &st;
    if (m2.Run() != sc::Status::kOk) return 1;
    m2_count[f] = count;
    broad[1][0] += st.box_tests, broad[1][1] += st.sphere_tests;
    m1.stats = &st;
    if (m1.Run() != sc::Status::kOk) return 1;
    m1_count[f] = count;
    broad[0][0] += st.box_tests, broad[0][1] += st.sphere_tests;
    m1.stats = m2.stats = nullptr;
  }
  // The peers test the radii DetectJob tests: grown by the asset's contact margin (schema v2; 0 for v1).
  const float margin = model.contact_margin();
  std::vector<std::vector<float>> gr(w.frames.size());
  for (size_t f = 0; f < w.frames.size(); ++f) {
    gr[f] = sr[f];
    for (float& r : gr[f]) r += margin;
  }
  std::vector<uint8_t> excluded(size_t{S} * S, 0);
  for (uint32_t a = 0; a < S; ++a)
    for (uint32_t b = 0; b < S; ++b) excluded[size_t{a} * S + b] = model.IsExcluded(a, b);
  // M1 cross-check: naive loop over the distinct pairs sharing a chain.
  uint32_t m1_distinct_tests = 0, excluded_pairs = 0;
  for (uint32_t a = 0; a < S; ++a)
    for (uint32_t b = a + 1; b < S; ++b) {
      m1_distinct_tests += (model.chain_mask(a) & model.chain_mask(b)) != 0;
      excluded_pairs += excluded[size_t{a} * S + b];
    }
  bool mismatch = false;
  for (size_t f = 0; f < w.frames.size(); ++f) {
    uint32_t n = 0;
    for (uint32_t a = 0; a < S; ++a)
      for (uint32_t b = a + 1; b < S; ++b) {
        const float dx = sx[f][b] - sx[f][a], dy = sy[f][b] - sy[f][a], dz = sz[f][b] - sz[f][a], rr = gr[f][b] + gr[f][a];
        n += (model.chain_mask(a) & model.chain_mask(b)) && dx * dx + dy * dy + dz * dz < rr * rr && !excluded[size_t{a} * S + b];
      }
    if (n != m1_count[f]) mismatch = true;
  }
  if (mismatch) std::fprintf(stderr, "MISMATCH: DetectJob M1 differs from a naive loop over the chain pairs\n");
  auto load_spheres = [&](size_t f) {
    std::copy(sx[f].begin(), sx[f].end(), ws.mutable_x());
    std::copy(sy[f].begin(), sy[f].end(), ws.mutable_y());
    std::copy(sz[f].begin(), sz[f].end(), ws.mutable_z());
    std::copy(sr[f].begin(), sr[f].end(), ws.mutable_r());
  };
  auto overlap = [&](size_t f, uint32_t a, uint32_t b) {
    const float dx = sx[f][a] - sx[f][b], dy = sy[f][a] - sy[f][b], dz = sz[f][a] - sz[f][b], rr = gr[f][a] + gr[f][b];
    return dx * dx + dy * dy + dz * dz < rr * rr && !excluded[size_t{a} * S + b];
  };
  const size_t F = w.frames.size();
  uint64_t fcl_tests = 0, bullet_tests = 0;  // sphere tests the peers ran after their AABB culling

  struct Row {
    const char* name;
    double us;
  };
  std::vector<Row> rows;
  // Best median of `runs` measurements (a loaded machine only ever makes a median slower).
  auto measure = [&](const char* name, const std::function<void(size_t)>& fn) {
    double best = 1e300;
    for (int k = 0; k < runs; ++k) best = std::min(best, MedianMicros(F, reps, fn));
    rows.push_back({name, best});
    return best;
  };
  const double refit_us = measure("sc refit", [&](size_t f) { set_frame(f); (void)refit.Run(); });
  // Detect-only rows reuse the stored spheres (copying 4·#S floats costs ~20 ns, included for all).
  measure("sc M1 detect", [&](size_t f) {
    load_spheres(f);
    (void)m1.Run();
    g_sink = g_sink + count;
  });
  const double m1_us = measure("sc refit+M1", [&](size_t f) {
    set_frame(f);
    (void)refit.Run();
    (void)m1.Run();
    g_sink = g_sink + count;
  });
  const double m2_us = measure("sc M2 detect", [&](size_t f) {
    load_spheres(f);
    (void)m2.Run();
    g_sink = g_sink + count;
  });
  measure("sc refit+M2", [&](size_t f) {
    set_frame(f);
    (void)refit.Run();
    (void)m2.Run();
    g_sink = g_sink + count;
  });
  (void)refit_us;
  if (has_fold) {  // what the asset's fold margin costs: the broad phase's hits of one region tested again
    sc::DetectJob m1_fold = m1, m2_fold = m2;
    m1_fold.fold_margin = m2_fold.fold_margin = -1.0f;  // the asset's
    measure("sc M1 det. fold mrg", [&](size_t f) {
      load_spheres(f);
      (void)m1_fold.Run();
      g_sink = g_sink + count;
    });
    measure("sc M2 det. fold mrg", [&](size_t f) {
      load_spheres(f);
      (void)m2_fold.Run();
      g_sink = g_sink + count;
    });
  }
  if (w.joints.size() == F) {
    sc::JointRefitJob joints;
    joints.model = &model;
    joints.workspace = &ws;
    joints.joint_count = view.asset->joint_count();
    measure("sc refit joints", [&](size_t f) {
      joints.joint_matrices = w.joints[f].data();
      (void)joints.Run();
    });
  }

  struct Aos {
    float x, y, z, r;
  };
  std::vector<Aos> aos(S);
  struct Peer {
    const char* name;
    double us;
  };
  std::vector<Peer> peers;
  peers.push_back({"naive M2", measure("naive M2", [&](size_t f) {
                     for (uint32_t i = 0; i < S; ++i) aos[i] = {sx[f][i], sy[f][i], sz[f][i], gr[f][i]};
                     uint32_t n = 0;
                     for (uint32_t a = 0; a < S; ++a)
                       for (uint32_t b = a + 1; b < S; ++b) {
                         const float dx = aos[a].x - aos[b].x, dy = aos[a].y - aos[b].y, dz = aos[a].z - aos[b].z;
                         const float rr = aos[a].r + aos[b].r;
                         if (dx * dx + dy * dy + dz * dz < rr * rr && !excluded[size_t{a} * S + b]) ++n;
                       }
                     if (n != m2_count[f]) mismatch = true;
                     g_sink = g_sink + n;
                   })});

#if SPHERECHAIN_BENCH_FCL
  {
    fcl::DynamicAABBTreeCollisionManager<float> manager;
    std::vector<std::shared_ptr<fcl::Sphere<float>>> shapes;
    std::vector<std::unique_ptr<fcl::CollisionObject<float>>> objects;
    for (uint32_t i = 0; i < S; ++i) {
      shapes.push_back(std::make_shared<fcl::Sphere<float>>(sr[0][i]));
      objects.push_back(std::make_unique<fcl::CollisionObject<float>>(shapes.back()));
      objects.back()->setUserData(reinterpret_cast<void*>(uintptr_t{i}));
      objects.back()->setTranslation(fcl::Vector3<float>(sx[0][i], sy[0][i], sz[0][i]));
      objects.back()->computeAABB();
      manager.registerObject(objects.back().get());
    }
    manager.setup();
    struct Data {
      std::function<bool(size_t, uint32_t, uint32_t)>* test;
      size_t frame;
      uint32_t n, tests;
    };
    std::function<bool(size_t, uint32_t, uint32_t)> test_fn = overlap;
    auto frame = [&](size_t f) {
      for (uint32_t i = 0; i < S; ++i) {
        shapes[i]->radius = gr[f][i];
        shapes[i]->computeLocalAABB();
        objects[i]->setTranslation(fcl::Vector3<float>(sx[f][i], sy[f][i], sz[f][i]));
        objects[i]->computeAABB();
      }
      manager.update();
      Data data{&test_fn, f, 0, 0};
      manager.collide(&data, [](fcl::CollisionObject<float>* o1, fcl::CollisionObject<float>* o2, void* p) {
        auto* d = static_cast<Data*>(p);
        uint32_t a = uint32_t(reinterpret_cast<uintptr_t>(o1->getUserData()));
        uint32_t b = uint32_t(reinterpret_cast<uintptr_t>(o2->getUserData()));
        if (a > b) std::swap(a, b);
        ++d->tests;
        if ((*d->test)(d->frame, a, b)) ++d->n;
        return false;
      });
      if (data.n != m2_count[f]) mismatch = true;
      g_sink = g_sink + data.n;
      return data.tests;
    };
    for (size_t f = 0; f < F; ++f) fcl_tests += frame(f);
    peers.push_back({"FCL DynAABBTree M2", measure("FCL DynAABBTree M2", [&](size_t f) { (void)frame(f); })});
  }
#endif
#if SPHERECHAIN_BENCH_BULLET
  {
    btDbvtBroadphase broadphase;
    std::vector<btBroadphaseProxy*> proxies;
    for (uint32_t i = 0; i < S; ++i) {
      const btVector3 c(sx[0][i], sy[0][i], sz[0][i]), e(sr[0][i], sr[0][i], sr[0][i]);
      proxies.push_back(broadphase.createProxy(c - e, c + e, 0, reinterpret_cast<void*>(uintptr_t{i}), 1, 1, nullptr));
    }
    auto frame = [&](size_t f) {
      for (uint32_t i = 0; i < S; ++i) {
        const btVector3 c(sx[f][i], sy[f][i], sz[f][i]), e(gr[f][i], gr[f][i], gr[f][i]);
        broadphase.setAabb(proxies[i], c - e, c + e, nullptr);
      }
      broadphase.calculateOverlappingPairs(nullptr);
      btOverlappingPairCache* cache = broadphase.getOverlappingPairCache();
      const int np = cache->getNumOverlappingPairs();
      btBroadphasePair* pairs = cache->getOverlappingPairArrayPtr();
      uint32_t n = 0;
      for (int k = 0; k < np; ++k) {
        uint32_t a = uint32_t(reinterpret_cast<uintptr_t>(pairs[k].m_pProxy0->m_clientObject));
        uint32_t b = uint32_t(reinterpret_cast<uintptr_t>(pairs[k].m_pProxy1->m_clientObject));
        if (a > b) std::swap(a, b);
        if (overlap(f, a, b)) ++n;
      }
      if (n != m2_count[f]) mismatch = true;
      g_sink = g_sink + n;
      return static_cast<uint32_t>(np);
    };
    for (size_t f = 0; f < F; ++f) bullet_tests += frame(f);
    peers.push_back({"Bullet btDbvt M2", measure("Bullet btDbvt M2", [&](size_t f) { (void)frame(f); })});
  }
#endif

  uint64_t m1_total = 0, m2_total = 0;
  for (size_t f = 0; f < F; ++f) m1_total += m1_count[f], m2_total += m2_count[f];
  sc::DetectStats st1, st2;
  m1.stats = &st1, m2.stats = &st2;
  (void)m1.Run(), (void)m2.Run();
  std::printf("pairs per frame (mean): M1 %.2f distinct, M2 %.2f; excluded pairs %u\n", double(m1_total) / F,
              double(m2_total) / F, excluded_pairs);
  std::printf("tests per frame: M1 %u (paper count, per chain; %u distinct pairs sharing a chain, each tested once), "
              "M2 %u, naive %u",
              st1.tests, m1_distinct_tests, st2.tests, st2.tests);
#if SPHERECHAIN_BENCH_FCL
  std::printf(", FCL %.1f sphere tests after AABB culling", double(fcl_tests) / F);
#endif
#if SPHERECHAIN_BENCH_BULLET
  std::printf(", Bullet %.1f", double(bullet_tests) / F);
#endif
  std::printf("\nbroad phase per frame (mean): M1 %.1f block-pair tests, %.1f sphere tests; M2 %.1f, %.1f\n",
              double(broad[0][0]) / F, double(broad[0][1]) / F, double(broad[1][0]) / F, double(broad[1][1]) / F);
  std::printf("%s\n", runs > 1 ? "(each row: best of the medians of several runs)" : "");
  std::printf("%-22s %12s %10s\n", "", "median us", "vs M2");
  for (const Row& r : rows) std::printf("%-22s %12.3f %10.2f\n", r.name, r.us, r.us / m2_us);
  std::printf("\n%-22s %14s %14s\n", "ratio (peer / sc)", "/ sc M2 det.", "/ sc refit+M1");
  for (const Peer& p : peers) std::printf("%-22s %13.1fx %13.1fx\n", p.name, p.us / m2_us, p.us / m1_us);
  if (!ManyCharacters(w, model, characters, runs)) mismatch = true;
  if (!NarrowPhase(w, view, runs, cgal_frames, per_frame, margin_scales)) mismatch = true;
  if (mismatch) {
    std::fprintf(stderr, "MISMATCH: a pair count differs (see above)\n");
    return 1;
  }
  return 0;
}
