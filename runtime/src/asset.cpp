// LoadAsset: envelope, FlatBuffers verification, semantic pass (see asset.h).
#include "spherechain/runtime/asset.h"

#include <cassert>
#include <cmath>
#include <cstring>

namespace spherechain::runtime {
namespace {

namespace fb = ::flatbuffers;
using schema::Asset;

constexpr fb::voffset_t kVtSchemaVersion = 4;  // Asset::VT_SCHEMA_VERSION (first field)
static_assert(kVtSchemaVersion == Asset::VT_SCHEMA_VERSION);

bool Finite(float v) { return std::isfinite(v); }
bool Finite(const schema::Vec3& v) { return Finite(v.x()) && Finite(v.y()) && Finite(v.z()); }

template <typename V>
uint32_t Len(const V* v) { return v ? v->size() : 0; }

Status ReadVersion(const uint8_t* buf, size_t size, uint32_t* version) {
  // Verify only the root table header and the schema_version field, so that a buffer from another
  // schema version gets a version status rather than a generic verification failure.
  fb::Verifier v(buf, size, /*max_depth=*/8, /*max_tables=*/4, /*check_alignment=*/true);
  const fb::uoffset_t root = fb::ReadScalar<fb::uoffset_t>(buf);
  if (root % 4 != 0 || root > size - sizeof(fb::uoffset_t)) return Status::kErrorCorrupt;
  const auto* table = reinterpret_cast<const fb::Table*>(buf + root);
  if (!table->VerifyTableStart(v) || !table->VerifyField<uint32_t>(v, kVtSchemaVersion, 4))
    return Status::kErrorCorrupt;
  *version = table->GetField<uint32_t>(kVtSchemaVersion, 0);
  return Status::kOk;
}

Status Semantics(const Asset& a, AssetView* view) {
  const auto* fp = a.fingerprint();
  const auto* spheres = a.spheres();
  const auto* chains = a.chains();
  const auto* offs = a.surrounding_offsets();
  const auto* surr = a.surrounding_triangles();
  const auto* piv_t = a.pivot_triangles();
  const auto* piv_v = a.pivot_vertices();
  const auto* frames = a.pivot_frames();
  if (!fp || !spheres || !chains || !offs || !surr || !piv_t || !piv_v || !frames)
    return Status::kErrorMissingField;

  const uint32_t S = spheres->size();
  const uint32_t V = fp->vertex_count();
  const uint32_t T = fp->triangle_count();
  if (S == 0) return Status::kErrorNoSpheres;
  if (S > kMaxSpheres) return Status::kErrorTooManySpheres;
  if (chains->size() > kMaxChains) return Status::kErrorTooManyChains;

  // Counts.
  if (frames->size() != S || piv_t->size() != size_t{4} * S || piv_v->size() != size_t{12} * S ||
      offs->size() != S + 1)
    return Status::kErrorCountMismatch;
  if ((a.spheres_phi1() && a.spheres_phi1()->size() != S) || (a.spheres_phi2() && a.spheres_phi2()->size() != S) ||
      (a.sphere_regions() && a.sphere_regions()->size() != S) || (a.sphere_labels() && a.sphere_labels()->size() != S))
    return Status::kErrorCountMismatch;
  if ((a.triangle_regions() && a.triangle_regions()->size() != T) ||
      (a.triangle_spheres() && a.triangle_spheres()->size() != T))
    return Status::kErrorCountMismatch;
  if (a.params() && a.params()->pivots_per_sphere() != kPivotsPerSphere) return Status::kErrorCountMismatch;

  // Floats.
  for (const schema::Sphere* s : *spheres) {
    if (!Finite(s->center()) || !Finite(s->radius())) return Status::kErrorNonFinite;
    if (!(s->radius() > 0.0f)) return Status::kErrorRadius;
  }
  for (const schema::PivotFrame* f : *frames) {
    if (!Finite(f->local_center()) || !Finite(f->centroid_offset()) || !Finite(f->mean_distance()))
      return Status::kErrorNonFinite;
    if (!(f->mean_distance() > 0.0f)) return Status::kErrorPivotFrame;
  }
  // The refit scales each radius by its pivots' spread against this one: the ratio must be a finite float.
  for (uint32_t s = 0; s < S; ++s)  // frames->size() == S (above)
    if (!std::isfinite(spheres->Get(s)->radius() / frames->Get(s)->mean_distance())) return Status::kErrorPivotFrame;
  if (!Finite(a.contact_margin())) return Status::kErrorNonFinite;  // NaN would silently detect nothing
  if (a.contact_margin() < 0.0f) return Status::kErrorContactMargin;
  // The fold margin (optional; < 0: none) is tested per region pair, so it needs the spheres' regions.
  if (!Finite(a.fold_margin())) return Status::kErrorNonFinite;
  if (a.fold_margin() >= 0.0f && !a.sphere_regions()) return Status::kErrorMissingField;

  // Chains: present, sorted, unique, in range, and with a bounded number of candidate pairs (M1's
  // workspace and DetectBound grow with Σ|ζ|(|ζ|−1)/2, so its chains alone cannot ask for gigabytes; M2's
  // grow with the pairs not excluded, up to #S²/2: a 7 MB asset of kMaxSpheres spheres and no exclusions
  // asks M2 for about 17 GB of keys (model.h: O(#S²)); not bounded here).
  uint64_t chain_pairs = 0;
  for (const schema::Chain* c : *chains) {
    const auto* list = c->spheres();
    if (!list) return Status::kErrorMissingField;
    for (uint32_t i = 0; i < list->size(); ++i) {
      if (list->Get(i) >= S) return Status::kErrorIndexOutOfRange;
      if (i > 0 && list->Get(i) <= list->Get(i - 1)) return Status::kErrorChainOrder;
    }
    chain_pairs += uint64_t{list->size()} * (list->size() - (list->size() ? 1 : 0)) / 2;
  }
  if (chain_pairs > kMaxChainPairs) return Status::kErrorTooManyChains;
  if (const auto* ex = a.excluded_pairs()) {
    uint32_t prev = 0;
    for (uint32_t i = 0; i < ex->size(); ++i) {
      const schema::SpherePair* p = ex->Get(i);
      if (p->a() >= S || p->b() >= S) return Status::kErrorIndexOutOfRange;
      const uint32_t key = (uint32_t{p->a()} << 16) | p->b();
      if (p->a() >= p->b() || (i > 0 && key <= prev)) return Status::kErrorExcludedPairs;
      prev = key;
    }
  }
  if (const auto* ts = a.triangle_spheres())
    for (uint16_t s : *ts)
      if (s >= S) return Status::kErrorIndexOutOfRange;

  // Surrounding regions.
  if (offs->Get(0) != 0 || offs->Get(S) != surr->size()) return Status::kErrorOffsets;
  for (uint32_t i = 0; i < S; ++i)
    if (offs->Get(i + 1) < offs->Get(i)) return Status::kErrorOffsets;
  for (uint32_t t : *surr)
    if (t >= T) return Status::kErrorIndexOutOfRange;
  // Reach regions (optional, both or neither): offsets like the surrounding regions', triangles ascending
  // within a sphere.
  const auto* roffs = a.reach_offsets();
  const auto* reach = a.reach_triangles();
  if (bool(roffs) != bool(reach)) return Status::kErrorMissingField;
  if (roffs) {
    if (roffs->size() != S + 1) return Status::kErrorCountMismatch;
    if (roffs->Get(0) != 0 || roffs->Get(S) != reach->size()) return Status::kErrorOffsets;
    // Every offset ascending first, so that each sphere's range lies within reach_triangles: checked one
    // sphere at a time, [0, 100, 5] over 5 triangles would walk sphere 0 past the end.
    for (uint32_t i = 0; i < S; ++i)
      if (roffs->Get(i + 1) < roffs->Get(i)) return Status::kErrorOffsets;
    for (uint32_t i = 0; i < S; ++i) {
      const uint32_t begin = roffs->Get(i), end = roffs->Get(i + 1);
      for (uint32_t k = begin; k < end; ++k) {
        if (reach->Get(k) >= T) return Status::kErrorIndexOutOfRange;
        if (k > begin && reach->Get(k) <= reach->Get(k - 1)) return Status::kErrorOffsets;
      }
    }
  }

  // Narrow-phase topology (optional): the index buffer and the weld ids.
  if (const auto* tris = a.triangles()) {
    if (tris->size() != size_t{3} * T) return Status::kErrorCountMismatch;
    for (uint32_t v : *tris)
      if (v >= V) return Status::kErrorIndexOutOfRange;
  }
  if (const auto* weld = a.weld_ids()) {
    if (weld->size() != V) return Status::kErrorCountMismatch;
    for (uint32_t v = 0; v < V; ++v) {
      const uint32_t w = weld->Get(v);
      if (w > v || weld->Get(w) != w) return Status::kErrorIndexOutOfRange;
    }
  }

  // The skin's contact definition (optional): #V bind positions, finite, with the index buffer and weld ids
  // they are measured on, and a crease > 0 (absent: < 0).
  if (!Finite(a.crease())) return Status::kErrorNonFinite;
  if (const auto* bind = a.bind_positions()) {
    if (bind->size() != size_t{3} * V) return Status::kErrorCountMismatch;
    for (float x : *bind)
      if (!std::isfinite(x)) return Status::kErrorNonFinite;
  }
  if (a.crease() == 0.0f) return Status::kErrorMissingField;  // neither absent (-1) nor a length
  if (a.crease() > 0.0f && (!a.bind_positions() || !a.triangles() || !a.weld_ids())) return Status::kErrorMissingField;

  // Pivots.
  for (uint32_t t : *piv_t)
    if (t >= T) return Status::kErrorIndexOutOfRange;
  for (uint32_t v : *piv_v)
    if (v >= V) return Status::kErrorIndexOutOfRange;

  // Joints are indexed by uint16 (sphere_joints, skin_joints): at most 65,536 of them.
  if (a.joint_count() > kMaxJoints) return Status::kErrorIndexOutOfRange;
  // Joint weights (optional, schema v3): four influences per sphere.
  const auto* sj = a.sphere_joints();
  const auto* sw = a.sphere_joint_weights();
  if (bool(sj) != bool(sw)) return Status::kErrorMissingField;
  if (sj) {
    if (sj->size() != size_t{4} * S || sw->size() != size_t{4} * S) return Status::kErrorCountMismatch;
    for (uint16_t j : *sj)
      if (j >= a.joint_count()) return Status::kErrorIndexOutOfRange;
    for (uint32_t i = 0; i < S; ++i) {
      float sum = 0.0f;
      for (uint32_t k = 0; k < 4; ++k) {
        const float w = sw->Get(4 * i + k);
        if (!std::isfinite(w) || w < 0.0f) return Status::kErrorSkinWeights;
        // The refit blends a sphere's influences up to its first 0 (the schema lists them by descending
        // weight): a weight after a 0 would be dropped.
        if (k > 0 && w > 0.0f && sw->Get(4 * i + k - 1) == 0.0f) return Status::kErrorSkinWeights;
        sum += w;
      }
      if (!(std::fabs(sum - 1.0f) <= 1e-3f)) return Status::kErrorSkinWeights;
    }
  }

  // The skin weights per vertex (optional, schema v4, with the crease rule): #V counts, their joints and
  // weights; a vertex's rounded weights sum to 255 within its count (each is within 1/2 of weight × 255).
  const auto* kc = a.skin_counts();
  const auto* kj = a.skin_joints();
  const auto* kw = a.skin_weights();
  if (bool(kc) != bool(kj) || bool(kc) != bool(kw)) return Status::kErrorMissingField;
  if (kc) {
    if (kc->size() != V || !(a.crease() > 0.0f)) return Status::kErrorCountMismatch;
    size_t n = 0;
    for (uint8_t c : *kc) n += c;
    if (kj->size() != n || kw->size() != n) return Status::kErrorCountMismatch;
    for (uint16_t j : *kj)
      if (j >= a.joint_count()) return Status::kErrorIndexOutOfRange;
    size_t e = 0;
    for (uint8_t c : *kc) {
      int sum = 0;
      for (uint32_t k = 0; k < c; ++k) sum += kw->Get(e++);
      if (c && std::abs(sum - 255) * 2 > int{c}) return Status::kErrorSkinWeights;
    }
  }

  // Regions (optional, schema v4): what region values mean; the trunk last. Every sphere and triangle
  // region value below their count, or below the paper's five without the table (RegionCount).
  uint32_t region_count = 5;
  if (const auto* regions = a.regions()) {
    region_count = regions->size();
    if (region_count < 2 || region_count > kMaxRegions) return Status::kErrorRegions;
    for (uint32_t r = 0; r < region_count; ++r)
      if ((regions->Get(r)->kind() == schema::RegionKind::Trunk) != (r + 1 == region_count)) return Status::kErrorRegions;
  }
  if (const auto* sr = a.sphere_regions())
    for (uint8_t r : *sr)
      if (r >= region_count) return Status::kErrorRegions;
  if (const auto* tr = a.triangle_regions())
    for (uint8_t r : *tr)
      if (r >= region_count) return Status::kErrorRegions;

  view->asset = &a;
  view->sphere_count = S;
  view->vertex_count = V;
  view->triangle_count = T;
  view->chain_count = chains->size();
  return Status::kOk;
}

}  // namespace

Status LoadAsset(const void* bytes, size_t size, AssetView* out) {
  if (!out) return Status::kErrorNullArgument;
  *out = AssetView{};
  if (!bytes) return Status::kErrorNullArgument;
  if (reinterpret_cast<uintptr_t>(bytes) % 8 != 0) return Status::kErrorAlignment;
  if (size < 2 * sizeof(fb::uoffset_t)) return Status::kErrorAssetTooSmall;
  if (size > kMaxAssetBytes) return Status::kErrorAssetTooLarge;
  const auto* buf = static_cast<const uint8_t*>(bytes);
  if (!fb::BufferHasIdentifier(buf, kFileIdentifier)) return Status::kErrorIdentifier;

  uint32_t version = 0;
  if (Status s = ReadVersion(buf, size, &version); s != Status::kOk) return s;
  if (version < kMinSchemaVersion) return Status::kErrorVersionTooOld;
  if (version > kSchemaVersion) return Status::kErrorVersionTooNew;

  fb::Verifier verifier(buf, size, /*max_depth=*/8, /*max_tables=*/16 + 1024 + 65536 + 256 + 256, /*check_alignment=*/true);
  if (!schema::VerifyAssetBuffer(verifier)) return Status::kErrorCorrupt;

  AssetView view;
  if (Status s = Semantics(*schema::GetAsset(buf), &view); s != Status::kOk) return s;
  *out = view;
  return Status::kOk;
}

TriangleSpan SurroundingTriangles(const AssetView& view, uint32_t sphere) {
  assert(view.valid() && sphere < view.sphere_count);
  if (!view.valid() || sphere >= view.sphere_count) return {};
  const auto* offs = view.asset->surrounding_offsets();
  const uint32_t begin = offs->Get(sphere), end = offs->Get(sphere + 1);
  if (begin == end) return {};
  return {view.asset->surrounding_triangles()->data() + begin, end - begin};
}

TriangleSpan ReachTriangles(const AssetView& view, uint32_t sphere) {
  assert(view.valid() && sphere < view.sphere_count);
  if (!view.valid() || sphere >= view.sphere_count) return {};
  const auto* offs = view.asset->reach_offsets();
  if (!offs) return SurroundingTriangles(view, sphere);
  const uint32_t begin = offs->Get(sphere), end = offs->Get(sphere + 1);
  if (begin == end) return {};
  return {view.asset->reach_triangles()->data() + begin, end - begin};
}

uint32_t RegionCount(const AssetView& view) {
  if (!view.valid()) return 0;
  return view.asset->regions() ? view.asset->regions()->size() : 5u;
}

const char* RegionName(const AssetView& view, uint32_t region) {
  static const char* const kPaper[5] = {"left_arm", "right_arm", "left_leg", "right_leg", "torso"};
  if (region >= RegionCount(view)) return "";
  if (const auto* regions = view.asset->regions()) {
    const auto* name = regions->Get(region)->name();
    return name ? name->c_str() : "";
  }
  return kPaper[region];
}

bool IsTrunkRegion(const AssetView& view, uint32_t region) {
  const uint32_t n = RegionCount(view);
  return n > 0 && region + 1 == n;
}

TriangleSpan PivotTriangles(const AssetView& view, uint32_t sphere) {
  if (!view.valid() || sphere >= view.sphere_count) return {};
  return {view.asset->pivot_triangles()->data() + size_t{4} * sphere, kPivotsPerSphere};
}

}  // namespace spherechain::runtime
