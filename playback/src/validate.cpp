// ValidateAsset: the checks of `spherechain validate`, as a library (validate.h).
#include "spherechain/playback/validate.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <span>

#include "spherechain/import/import.h"
#include "spherechain/import/vertex_contract.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/session.h"
#include "spherechain/runtime/runtime.h"

namespace spherechain::playback {

namespace {

Finding Make(std::string code, Severity severity, FindingLocation where, std::string message) {
  return Finding{std::move(code), severity, std::move(where), std::move(message)};
}

FindingLocation At(const std::string& file, int32_t sphere = -1, int32_t chain = -1, std::string field = {}) {
  FindingLocation l;
  l.file = file;
  l.sphere = sphere;
  l.chain = chain;
  l.field = std::move(field);
  return l;
}

bool Finite(float v) { return std::isfinite(v); }

/// For a semantic rejection (the FlatBuffer itself verified): the first sphere / chain / field that
/// explains `status`, found by re-checking the arrays the way LoadAsset does. The file alone when the
/// status names nothing this can locate.
FindingLocation LocateRejection(const uint8_t* bytes, runtime::Status status, const std::string& file) {
  FindingLocation where = At(file);
  const uint32_t code = static_cast<uint32_t>(status);
  if ((code & 0xFFFF'FF00u) != 0x8000'0200u) return where;  // envelope / structure: nothing to point at
  const schema::Asset* a = schema::GetAsset(bytes);
  const auto* spheres = a->spheres();
  const uint32_t S = spheres ? spheres->size() : 0;
  switch (status) {
    case runtime::Status::kErrorRadius:
      for (uint32_t s = 0; s < S; ++s)
        if (spheres->Get(s)->radius() <= 0.0f) return At(file, int32_t(s), -1, "spheres.radius");
      break;
    case runtime::Status::kErrorNonFinite:
      for (uint32_t s = 0; s < S; ++s) {
        const schema::Sphere* sp = spheres->Get(s);
        if (!Finite(sp->center().x()) || !Finite(sp->center().y()) || !Finite(sp->center().z()))
          return At(file, int32_t(s), -1, "spheres.center");
        if (!Finite(sp->radius())) return At(file, int32_t(s), -1, "spheres.radius");
      }
      if (!Finite(a->contact_margin())) return At(file, -1, -1, "contact_margin");
      if (!Finite(a->fold_margin())) return At(file, -1, -1, "fold_margin");
      where.field = "pivot_frames";
      break;
    case runtime::Status::kErrorContactMargin:
      where.field = "contact_margin";
      break;
    case runtime::Status::kErrorChainOrder:
    case runtime::Status::kErrorIndexOutOfRange:
    case runtime::Status::kErrorTooManyChains:
      if (const auto* chains = a->chains()) {
        for (uint32_t c = 0; c < chains->size(); ++c) {
          const auto* list = chains->Get(c)->spheres();
          if (!list) continue;
          for (uint32_t i = 0; i < list->size(); ++i) {
            if (list->Get(i) >= S) return At(file, int32_t(list->Get(i)), int32_t(c), "chains.spheres");
            if (i > 0 && list->Get(i) <= list->Get(i - 1)) return At(file, int32_t(list->Get(i)), int32_t(c), "chains.spheres");
          }
        }
      }
      if (status == runtime::Status::kErrorIndexOutOfRange) where.field = "excluded_pairs / triangle_spheres / surrounding_triangles / pivot_triangles / pivot_vertices";
      else if (status == runtime::Status::kErrorTooManyChains) where.field = "chains";
      break;
    case runtime::Status::kErrorMissingField:
      if (!a->fingerprint()) where.field = "fingerprint";
      else if (!spheres) where.field = "spheres";
      else if (!a->chains()) where.field = "chains";
      else if (!a->surrounding_offsets()) where.field = "surrounding_offsets";
      else if (!a->pivot_frames()) where.field = "pivot_frames";
      else if (a->fold_margin() >= 0.0f && !a->sphere_regions()) where.field = "sphere_regions (a fold margin needs them)";
      break;
    case runtime::Status::kErrorCountMismatch:
      if (a->pivot_frames() && a->pivot_frames()->size() != S) where.field = "pivot_frames";
      else if (a->surrounding_offsets() && a->surrounding_offsets()->size() != S + 1) where.field = "surrounding_offsets";
      else if (a->sphere_regions() && a->sphere_regions()->size() != S) where.field = "sphere_regions";
      else if (a->pivot_triangles() && a->pivot_triangles()->size() != 4 * S) where.field = "pivot_triangles";
      else if (a->pivot_vertices() && a->pivot_vertices()->size() != 12 * S) where.field = "pivot_vertices";
      break;
    case runtime::Status::kErrorOffsets:
      where.field = "surrounding_offsets";
      break;
    case runtime::Status::kErrorExcludedPairs:
      where.field = "excluded_pairs";
      break;
    case runtime::Status::kErrorPivotFrame:
      if (const auto* frames = a->pivot_frames())
        for (uint32_t s = 0; s < frames->size(); ++s)
          if (!(frames->Get(s)->mean_distance() > 0.0f)) return At(file, int32_t(s), -1, "pivot_frames.mean_distance");
      break;
    case runtime::Status::kErrorSkinWeights:
      where.field = "sphere_joint_weights";
      break;
    default:
      break;
  }
  return where;
}

/// The asset's own consistency beyond what LoadAsset refuses: plausibility checks its bake failed and
/// was forced past (Asset.forced_findings), then spheres M1 or the narrow phase cannot see.
void CheckAsset(const runtime::AssetView& view, const std::string& file, std::vector<Finding>* out) {
  if (const auto* forced = view.asset->forced_findings())
    for (const schema::BakeFinding* f : *forced) {
      const std::string code = f->code() && f->code()->size() ? f->code()->str() : std::string("PLAUS-UNKNOWN");
      out->push_back(Make(code, Severity::kError, At(file, -1, -1, "forced_findings"),
                          "baked with --force although a plausibility check failed: " +
                              (f->message() ? f->message()->str() : std::string()) + " (fix the segmentation and re-bake)"));
    }
  const uint32_t S = view.sphere_count;
  std::vector<uint8_t> in_chain(S, 0);
  if (const auto* chains = view.asset->chains())
    for (uint32_t c = 0; c < chains->size(); ++c)
      if (const auto* list = chains->Get(c)->spheres())
        for (uint16_t s : *list)
          if (s < S) in_chain[s] = 1;
  for (uint32_t s = 0; s < S; ++s) {
    if (!in_chain[s])
      out->push_back(Make("SPHERE-NO-CHAIN", Severity::kWarning, At(file, int32_t(s), -1, "chains"),
                          "sphere " + std::to_string(s) + " is in no chain: M1 never tests it (M2 does)"));
    if (runtime::SurroundingTriangles(view, s).count == 0)
      out->push_back(Make("SPHERE-NO-REGION", Severity::kWarning, At(file, int32_t(s), -1, "surrounding_offsets"),
                          "sphere " + std::to_string(s) +
                              " has an empty surrounding region: the narrow phase cannot confirm its contacts"));
  }
}

/// Fingerprint, then the bind pose through the frame pipeline (refit + M2 detect).
void CheckMesh(const runtime::AssetView& view, const import::Mesh& mesh, const ValidateNames& names,
               std::vector<Finding>* out) {
  const import::Fingerprint fp = import::ComputeFingerprint(mesh);
  const auto* f = view.asset->fingerprint();
  if (fp.vertex_count != f->vertex_count() || fp.triangle_count != f->triangle_count()) {
    out->push_back(Make("FP-COUNTS", Severity::kError, At(names.mesh, -1, -1, "fingerprint"),
                        "mesh has " + std::to_string(fp.vertex_count) + " vertices / " +
                            std::to_string(fp.triangle_count) + " triangles, the asset was baked from " +
                            std::to_string(f->vertex_count()) + " / " + std::to_string(f->triangle_count()) +
                            (fp.vertex_count != f->vertex_count()
                                 ? " (" + import::DescribeVertexMismatch(view, fp.vertex_count) + ")"
                                 : std::string())));
    return;
  }
  if (fp.indices_hash != f->indices_hash())
    out->push_back(Make("FP-INDICES", Severity::kError, At(names.mesh, -1, -1, "fingerprint.indices_hash"),
                        "triangle indices differ from the baked mesh (re-bake the asset)"));
  if (fp.positions_hash != f->positions_hash())
    out->push_back(Make("FP-POSITIONS", Severity::kError, At(names.mesh, -1, -1, "fingerprint.positions_hash"),
                        "bind positions differ from the baked mesh (moved vertices? re-bake the asset; play, evaluate, "
                        "view and check refuse this pair)"));
  // The bind pose must report no self-collision: the frame pipeline (Session) on the bind positions, M2 alone.
  SessionOptions so;
  so.m1 = false;
  Session session;
  runtime::Status s = runtime::Status::kOk;
  if (!session.Init(view, mesh, so).ok() ||
      !session.Run(mesh.positions.data(), nullptr, SessionFrame::kBind, "bind").ok())
    // A runtime job's status; else the one configuration error reachable here: the vertex counts differ.
    s = session.runtime_status() != runtime::Status::kOk ? session.runtime_status() : runtime::Status::kErrorVertexCount;
  const std::span<const runtime::Collision> pairs =
      runtime::Succeeded(s) ? session.frame().m2 : std::span<const runtime::Collision>();
  const uint32_t count = uint32_t(pairs.size());
  if (runtime::Failed(s)) out->push_back(Make("RUNTIME", Severity::kError, At(names.asset), runtime::ToString(s)));
  for (uint32_t i = 0; i < count; ++i) {
    FindingLocation where = At(names.asset, pairs[i].a);
    where.other_sphere = pairs[i].b;
    where.field = "spheres";
    out->push_back(Make("BIND-COLLISION", Severity::kError, std::move(where),
                        "the bind pose reports a self-collision (depth " + std::to_string(pairs[i].depth) + ")"));
  }
}

}  // namespace

const char* ToString(Severity s) { return s == Severity::kError ? "error" : "warning"; }

std::string FindingLocation::ToString() const {
  if (sphere >= 0 && other_sphere >= 0) return "spheres " + std::to_string(sphere) + "," + std::to_string(other_sphere);
  std::string s = file;
  if (sphere >= 0) s += " sphere " + std::to_string(sphere);
  if (chain >= 0) s += " chain " + std::to_string(chain);
  if (!field.empty() && (sphere >= 0 || chain >= 0 || file.empty())) s += " field " + field;
  return s;
}

size_t CountErrors(const std::vector<Finding>& findings) {
  size_t n = 0;
  for (const Finding& f : findings) n += f.severity == Severity::kError;
  return n;
}

std::vector<Finding> ValidateAsset(const runtime::AssetView& view, const import::Mesh* mesh, const ValidateNames& names) {
  std::vector<Finding> out;
  if (!view.valid()) {
    out.push_back(Make("SPHC-LOAD", Severity::kError, At(names.asset),
                       "'" + names.asset + "' is not a loaded asset (AssetView not valid)"));
    return out;
  }
  CheckAsset(view, names.asset, &out);
  if (mesh) CheckMesh(view, *mesh, names, &out);
  return out;
}

std::vector<Finding> ValidateAssetBytes(const uint8_t* bytes, size_t size, const import::Mesh* mesh,
                                        const ValidateNames& names) {
  import::LoadedAsset asset;
  if (auto s = import::LoadAssetBytes(size ? bytes : nullptr, size, "'" + names.asset + "'", &asset); !s.ok())
    return {Make("SPHC-LOAD", Severity::kError, LocateRejection(asset.bytes(), asset.status, names.asset),
                 s.error().message)};
  return ValidateAsset(asset.view, mesh, names);
}

std::vector<Finding> ValidateAssetFile(const std::string& asset_path, const std::string& mesh_path,
                                       const std::string& rig_path, import::Context* log,
                                       import::VertexContract vertices) {
  ValidateNames names{asset_path, mesh_path};
  auto bytes = import::ReadFileBytes(asset_path, runtime::kMaxAssetBytes);
  if (!bytes.ok()) return {Make("SPHC-LOAD", Severity::kError, At(asset_path), bytes.error().message)};
  if (mesh_path.empty()) return ValidateAssetBytes(bytes->data(), bytes->size(), nullptr, names);
  // The asset first: an unloadable asset is reported without importing the mesh.
  import::LoadedAsset asset;
  if (!import::LoadAssetBytes(bytes->data(), bytes->size(), "'" + asset_path + "'", &asset).ok())
    return ValidateAssetBytes(bytes->data(), bytes->size(), nullptr, names);
  std::vector<Finding> out = ValidateAsset(asset.view, nullptr, names);
  import::ImportOptions opts;
  opts.rig_path = rig_path;
  opts.read_clips = false;
  opts.vertices = vertices == import::VertexContract::kAuto ? import::ContractForReimport(asset.view, mesh_path)  // the asset's own
                                                            : vertices;
  auto mesh = import::ImportMesh(mesh_path, opts, log);
  if (!mesh.ok()) {
    out.push_back(Make("MESH-IMPORT", Severity::kError, At(mesh_path), mesh.error().message));
    return out;
  }
  return ValidateAsset(asset.view, &mesh.value(), names);
}

}  // namespace spherechain::playback
