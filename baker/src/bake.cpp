#include "spherechain/baker/bake.h"
#include "spherechain/baker/training_poses.h"
#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/crease.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <type_traits>
#include <sstream>

namespace spherechain::baker {

using nlohmann::json;

// ---------------------------------------------------------------------------------------------------
// Configuration

namespace {

const char* MethodName(SegmentMethod m) {
  switch (m) {
    case SegmentMethod::kRig: return "rig";
    case SegmentMethod::kGeometry: return "geometry";
    case SegmentMethod::kSkeleton: return "skeleton";
    case SegmentMethod::kAuto: break;
  }
  return "auto";
}

template <class T>
Status ReadNumber(const json& j, const char* key, T lo, T hi, T* out, const std::string& where) {
  if (!j.contains(key)) return Ok{};
  const json& v = j.at(key);
  if (!v.is_number())
    return MakeError(Error::Code::kConfig, where + ": '" + key + "' must be a number");
  const double d = v.get<double>();
  if constexpr (std::is_integral_v<T>)
    if (std::isfinite(d) && d != std::floor(d))
      return MakeError(Error::Code::kConfig, where + ": '" + key + "' = " + v.dump() + " must be a whole number");
  if (!std::isfinite(d) || d < double(lo) || d > double(hi)) {
    std::ostringstream m;
    m << where << ": '" << key << "' = " << d << " is out of range [" << lo << ", " << hi << "]";
    return MakeError(Error::Code::kConfig, m.str());
  }
  *out = static_cast<T>(d);
  return Ok{};
}

// The fold margin the bake writes, relative to the body height; < 0: none (BakeConfig::fold_margin_rel).
double FoldMarginRel(const BakeConfig& config, const RegionLayout& layout) {
  if (config.fold_margin_rel) return *config.fold_margin_rel;
  const bool extended_biped = layout.paper && !layout.IsPaperFive();
  return extended_biped ? 0.0015 : -1.0;
}

}  // namespace

Result<BakeConfig> ParseBakeConfig(const std::string& text, const std::string& where) {
  json j;
  try {
    j = json::parse(text);
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kConfig, where + ": not valid JSON: " + e.what());
  }
  if (!j.is_object()) return MakeError(Error::Code::kConfig, where + ": the configuration must be a JSON object");
  static const std::set<std::string> known = {"segmentation", "region_map", "rig", "rays", "spheres_per_level",
                                              "disk_step", "disk_step_rel", "penetration_depth", "chains",
                                              "compare_segmentations", "fit", "max_spheres", "cover_voxel_rel", "cover_max_voxels",
                                              "min_radius_rel", "min_gain", "region_balance", "refine_sweeps", "dilation_rel",
                                              "skin_spheres", "skin_tolerance_rel", "skin_min_vertices", "medial_min_rel",
                                              "contact_margin_rel", "near_rel", "vertices", "regions", "pivot_poses",
                                              "pivot_pose_angle", "reach_rel", "fold_margin_rel", "crease_rel",
                                              "skin_weights"};
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!known.count(it.key())) return MakeError(Error::Code::kConfig, where + ": unknown key '" + it.key() + "'");

  BakeConfig c;
  if (j.contains("segmentation")) {
    if (!j["segmentation"].is_string()) return MakeError(Error::Code::kConfig, where + ": 'segmentation' must be a string");
    const std::string m = j["segmentation"];
    if (m == "auto") c.segmentation = SegmentMethod::kAuto;
    else if (m == "rig") c.segmentation = SegmentMethod::kRig;
    else if (m == "geometry") c.segmentation = SegmentMethod::kGeometry;
    else if (m == "skeleton") c.segmentation = SegmentMethod::kSkeleton;
    else if (m != "map")
      return MakeError(Error::Code::kConfig,
                       where + ": 'segmentation' must be auto, rig, geometry, skeleton or map, not '" + m + "'");
    if (m == "map" && !j.contains("region_map"))
      return MakeError(Error::Code::kConfig, where + ": segmentation 'map' needs 'region_map'");
    if (m != "map" && j.contains("region_map"))
      return MakeError(Error::Code::kConfig, where + ": segmentation '" + m +
                                                 "' and a 'region_map' both given: a region map is the segmentation "
                                                 "('map'); drop one");
  }
  for (const char* key : {"region_map", "rig"}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_string()) return MakeError(Error::Code::kConfig, where + ": '" + key + "' must be a path string");
  }
  if (j.contains("region_map")) c.region_map = j["region_map"];
  if (j.contains("rig")) c.import.rig_path = j["rig"];
  if (j.contains("regions")) {
    const std::string v = j["regions"].is_string() ? j["regions"].get<std::string>() : std::string();
    if (v == "extended") c.regions = RegionSet::kExtended;
    else if (v == "paper") c.regions = RegionSet::kPaper;
    else return MakeError(Error::Code::kConfig, where + ": 'regions' must be \"extended\" or \"paper\"");
  }
  if (j.contains("vertices")) {  // import.h VertexContract
    const std::string v = j["vertices"].is_string() ? j["vertices"].get<std::string>() : std::string();
    if (v == "joined") c.import.vertices = VertexContract::kJoined;
    else if (v == "source") c.import.vertices = VertexContract::kSource;
    else return MakeError(Error::Code::kConfig, where + ": 'vertices' must be \"joined\" or \"source\"");
  }
  if (j.contains("skin_weights")) {
    if (!j["skin_weights"].is_boolean()) return MakeError(Error::Code::kConfig, where + ": 'skin_weights' must be true or false");
    c.skin_weights = j["skin_weights"];
  }
  if (j.contains("compare_segmentations")) {
    if (!j["compare_segmentations"].is_boolean())
      return MakeError(Error::Code::kConfig, where + ": 'compare_segmentations' must be true or false");
    c.compare_segmentations = j["compare_segmentations"];
  }
  if (j.contains("fit")) {
    if (!j["fit"].is_string()) return MakeError(Error::Code::kConfig, where + ": 'fit' must be a string");
    const std::string m = j["fit"];
    if (m == "cover") c.fit.method = FitMethod::kCover;
    else if (m == "paper") c.fit.method = FitMethod::kPaper;
    else return MakeError(Error::Code::kConfig, where + ": 'fit' must be cover or paper, not '" + m + "'");
  }
  Status s = ReadNumber(j, "rays", 8, 4096, &c.fit.rays, where);
  if (s.ok()) s = ReadNumber(j, "max_spheres", 5, 4096, &c.fit.max_spheres, where);
  if (s.ok()) s = ReadNumber(j, "cover_voxel_rel", 1e-3, 0.1, &c.fit.cover_voxel_rel, where);
  if (s.ok()) s = ReadNumber(j, "cover_max_voxels", 0, 100'000'000, &c.fit.cover_max_voxels, where);
  if (s.ok()) s = ReadNumber(j, "min_radius_rel", 0.0, 0.2, &c.fit.min_radius_rel, where);
  if (s.ok()) s = ReadNumber(j, "min_gain", 0.0, 1.0, &c.fit.min_gain, where);
  if (s.ok()) s = ReadNumber(j, "region_balance", 0.0, 1.0, &c.fit.region_balance, where);
  if (s.ok()) s = ReadNumber(j, "refine_sweeps", 0, 64, &c.fit.refine_sweeps, where);
  if (s.ok()) s = ReadNumber(j, "dilation_rel", 0.0, 0.05, &c.fit.dilation_rel, where);
  if (s.ok()) s = ReadNumber(j, "skin_spheres", 0, 4091, &c.fit.skin_spheres, where);
  if (s.ok()) s = ReadNumber(j, "skin_tolerance_rel", 0.0, 0.2, &c.fit.skin_tolerance_rel, where);
  if (s.ok()) s = ReadNumber(j, "skin_min_vertices", 1, 1000000, &c.fit.skin_min_vertices, where);
  if (s.ok()) s = ReadNumber(j, "medial_min_rel", 0.0001, 1.0, &c.fit.medial_min_rel, where);
  if (s.ok()) s = ReadNumber(j, "contact_margin_rel", 0.0, 0.05, &c.contact_margin_rel, where);
  if (s.ok()) s = ReadNumber(j, "near_rel", 0.0, 0.2, &c.near_rel, where);
  if (s.ok() && j.contains("fold_margin_rel")) {
    double v = 0.0;
    s = ReadNumber(j, "fold_margin_rel", -1.0, 0.05, &v, where);
    if (s.ok()) c.fold_margin_rel = v < 0.0 ? -1.0 : v;
  }
  if (s.ok()) s = ReadNumber(j, "reach_rel", 0.0, 0.05, &c.reach_rel, where);
  if (s.ok()) s = ReadNumber(j, "crease_rel", 1e-6, 0.5, &c.crease_rel, where);
  if (s.ok()) s = ReadNumber(j, "pivot_poses", 0u, 256u, &c.pivot_poses, where);
  if (s.ok()) s = ReadNumber(j, "pivot_pose_angle", 0.0, 90.0, &c.pivot_pose_angle, where);
  if (s.ok()) s = ReadNumber(j, "spheres_per_level", 2, 2, &c.fit.spheres_per_level, where);
  if (s.ok()) s = ReadNumber(j, "disk_step", 1e-9, 1e9, &c.fit.disk_step, where);
  if (s.ok()) s = ReadNumber(j, "disk_step_rel", 1e-4, 0.5, &c.fit.disk_step_rel, where);
  if (s.ok()) s = ReadNumber(j, "penetration_depth", 0.0, 0.9, &c.fit.penetration_depth, where);
  if (!s.ok()) return s.error();
  if (j.contains("chains")) {
    const json& cj = j["chains"];
    if (!cj.is_array() || cj.empty())
      return MakeError(Error::Code::kConfig, where + ": 'chains' must be a non-empty array");
    c.chains.clear();
    for (size_t i = 0; i < cj.size(); ++i) {
      const json& e = cj[i];
      const std::string at = where + ": chains[" + std::to_string(i) + "]";
      if (!e.is_object() || !e.contains("members") || !e["members"].is_array())
        return MakeError(Error::Code::kConfig, at + " must be {\"name\": ..., \"members\": [...]}");
      ChainDef d;
      if (e.contains("name") && !e["name"].is_string())
        return MakeError(Error::Code::kConfig, at + ": name must be a string");
      d.name = e.contains("name") ? e["name"].get<std::string>() : "chain" + std::to_string(i);
      for (const json& m : e["members"]) {
        if (!m.is_string()) return MakeError(Error::Code::kConfig, at + ": members must be strings");
        d.members.push_back(m);
      }
      c.chains.push_back(std::move(d));
    }
  }
  return c;
}

Result<BakeConfig> LoadBakeConfig(const std::string& path, Context* ctx) {
  auto bytes = ReadFileBytes(path, 16u << 20);
  if (!bytes.ok()) return bytes.error();
  if (ctx) ctx->RecordFileRead(path);
  auto config = ParseBakeConfig(std::string(bytes->begin(), bytes->end()), path);
  if (!config.ok()) return config;
  // A configuration names its region map and rig relative to its own folder (it travels with them, and a
  // build system runs the bake from another folder).
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  for (std::string* p : {&config->region_map, &config->import.rig_path})
    if (!p->empty() && std::filesystem::path(*p).is_relative() && !dir.empty()) *p = (dir / *p).string();
  return config;
}

Status ApplyBakeOptions(const BakeOptions& o, BakeConfig* config) {
  auto bad = [](const char* option, const std::string& value, const char* choices) {
    return MakeError(Error::Code::kConfig,
                     std::string(option) + ": '" + value + "' is not one of " + choices);
  };
  if (!o.rig.empty()) config->import.rig_path = o.rig;
  if (o.vertices == "joined") config->import.vertices = VertexContract::kJoined;
  else if (o.vertices == "source") config->import.vertices = VertexContract::kSource;
  else if (!o.vertices.empty()) return bad("vertices", o.vertices, "joined, source");
  if (!o.region_map.empty()) config->region_map = o.region_map;
  if (o.regions == "paper") config->regions = RegionSet::kPaper;
  else if (o.regions == "extended") config->regions = RegionSet::kExtended;
  else if (!o.regions.empty()) return bad("regions", o.regions, "extended, paper");
  if (!(o.disk_step >= 0.0) || !std::isfinite(o.disk_step))
    return MakeError(Error::Code::kConfig, "disk_step: " + std::to_string(o.disk_step) +
                                               " must be > 0 (source units), or 0 for the default");
  if (o.disk_step > 0.0) config->fit.disk_step = o.disk_step;
  config->force = o.force;
  if (o.skin_weights) config->skin_weights = true;
  const bool method = o.segmentation == "auto" || o.segmentation == "rig" || o.segmentation == "geometry" ||
                      o.segmentation == "skeleton";
  if (method && !o.region_map.empty())
    return MakeError(Error::Code::kConfig, "segmentation '" + o.segmentation +
                                               "' and --region-map both given: a region map is the segmentation ('map')");
  if (method) config->region_map.clear();  // the option overrides the configuration's region map
  if (o.segmentation == "auto") config->segmentation = SegmentMethod::kAuto;
  else if (o.segmentation == "rig") config->segmentation = SegmentMethod::kRig;
  else if (o.segmentation == "geometry") config->segmentation = SegmentMethod::kGeometry;
  else if (o.segmentation == "skeleton") config->segmentation = SegmentMethod::kSkeleton;
  else if (o.segmentation == "map") {
    if (config->region_map.empty())
      return MakeError(Error::Code::kConfig, "segmentation 'map' needs a region map (region_map, CLI --region-map)");
  } else if (!o.segmentation.empty()) {
    return bad("segmentation", o.segmentation, "auto, rig, geometry, skeleton, map");
  }
  return Ok{};
}

std::string CanonicalConfig(const BakeConfig& c, const RegionLayout* layout) {
  json j;  // nlohmann::json objects are key-sorted: stable
  j["segmentation"] = c.region_map.empty() ? MethodName(c.segmentation) : "map";
  j["fit"] = FitMethodName(c.fit.method);
  // Added with the extended layout: written only for it, so paper-layout and creature bakes hash exactly as
  // every asset before it did. With the bake's layout: only when the extended regions were made (a creature or a
  // paper fit asked for them keeps its own); without: as configured.
  const bool extended = layout ? layout->paper && !layout->IsPaperFive()
                               : c.regions == RegionSet::kExtended && c.fit.method == FitMethod::kCover;
  if (extended) j["regions"] = "extended";
  if (c.import.vertices != VertexContract::kAuto) j["vertices"] = ToString(c.import.vertices);
  if (c.fit.method == FitMethod::kCover) {
    j["max_spheres"] = c.fit.max_spheres;
    j["cover_voxel_rel"] = c.fit.cover_voxel_rel;
    // Added after assets were cached on the hash: written only when not the default (as "vertices").
    if (c.fit.cover_max_voxels != FitParams().cover_max_voxels) j["cover_max_voxels"] = c.fit.cover_max_voxels;
    j["min_radius_rel"] = c.fit.min_radius_rel;
    j["min_gain"] = c.fit.min_gain;
    j["refine_sweeps"] = c.fit.refine_sweeps;
    j["region_balance"] = c.fit.region_balance;
    j["dilation_rel"] = c.fit.dilation_rel;
    j["skin_spheres"] = layout ? SkinSpheres(c.fit, *layout) : c.fit.skin_spheres;
    j["skin_tolerance_rel"] = c.fit.skin_tolerance_rel;
    j["skin_min_vertices"] = c.fit.skin_min_vertices;
    j["medial_min_rel"] = c.fit.medial_min_rel;
  }
  j["contact_margin_rel"] = c.contact_margin_rel;
  j["near_rel"] = c.near_rel;
  j["reach_rel"] = c.reach_rel;
  if (c.fold_margin_rel) j["fold_margin_rel"] = *c.fold_margin_rel;  // added later: written only when set
  j["crease_rel"] = c.crease_rel;
  if (c.skin_weights) j["skin_weights"] = true;  // added later: written only when on
  // Added after assets were cached on the hash: written only when on (the default is off).
  if (c.pivot_poses) j["pivot_poses"] = c.pivot_poses, j["pivot_pose_angle"] = c.pivot_pose_angle;
  j["rays"] = c.fit.rays;
  j["spheres_per_level"] = c.fit.spheres_per_level;
  j["disk_step"] = c.fit.disk_step;
  j["disk_step_rel"] = c.fit.disk_step_rel;
  j["penetration_depth"] = c.fit.penetration_depth;
  json chains = json::array();
  for (const ChainDef& d : c.chains) chains.push_back({{"name", d.name}, {"members", d.members}});
  j["chains"] = chains;
  return j.dump();
}

// ---------------------------------------------------------------------------------------------------
// Bake

namespace {

/// The refusal of a body that failed plausibility checks: every finding, code first.
Error Refuse(const Mesh& mesh, const std::vector<PlausibilityFinding>& findings) {
  std::string why;
  for (const PlausibilityFinding& f : findings) why += (why.empty() ? "" : "; ") + f.code + ": " + f.message;
  return MakeError(Error::Code::kImplausible,
                   mesh.source_path + ": the bake looks wrong, refused (nothing written): " + why +
                       ". Check the segmentation (--segmentation, --region-map, --rig); --force writes the asset "
                       "anyway with these findings recorded in it");
}

bool IsTableOneChains(const std::vector<ChainDef>& defs) {
  const std::vector<ChainDef> table = DefaultChainDefs();
  if (defs.size() != table.size()) return false;
  for (size_t i = 0; i < defs.size(); ++i)
    if (defs[i].name != table[i].name || defs[i].members != table[i].members) return false;
  return true;
}

bool HasFinding(const std::vector<PlausibilityFinding>& findings, const std::string& code) {
  return std::any_of(findings.begin(), findings.end(), [&](const PlausibilityFinding& f) { return f.code == code; });
}

/// A creature's adjacency beyond BindExcludedPairs (the any-skeleton path), pairs not in `excluded`:
/// - sphere pairs whose surrounding regions' triangles already intersect at bind pose: a creature model
///   often passes through its own skin at rest (horns, eyes, a tail's tuft), and those triangles touch
///   in every frame without any collision (the bind_overlap rule's reason, met by the triangles);
/// - pairs of spheres of two limbs whose regions share skin (a quadruped's neck and its fore legs at the
///   chest, the tail and the hind legs), within 1.25 (rA + rB) + near at bind: the crease where they
///   leave the trunk side by side, as a limb and the torso at the hip (BindExcludedPairs' junction rule).
/// Humans skip it: the exact intersection test would cost MakeHuman ~0.1 s of its bake, and the human
/// assets stay as they were. Errors: those of ExactSelfIntersections.
struct CreatureExclusions {
  std::set<SpherePair> pairs;
  size_t bind_contacts = 0, creases = 0, triangle_pairs = 0;
};
Result<CreatureExclusions> CreatureExcludedPairs(const Mesh& mesh, const Segmentation& seg,
                                                 const std::vector<FittedSphere>& spheres,
                                                 const SurroundingRegions& surrounding,
                                                 const std::vector<SpherePair>& excluded, double near) {
  CreatureExclusions out;
  const std::vector<uint32_t> weld = ComputeWeldIds(mesh.positions);
  auto contacts = ExactSelfIntersections(mesh.positions.data(), mesh.vertex_count(), mesh.indices, weld);
  if (!contacts.ok()) return contacts.error();
  out.triangle_pairs = contacts->size();
  auto known = [&](const SpherePair& p) {
    return out.pairs.count(p) > 0 || std::binary_search(excluded.begin(), excluded.end(), p);
  };
  for (const TrianglePair& p : contacts.value()) {
    uint16_t a = surrounding.triangle_spheres[p.a], b = surrounding.triangle_spheres[p.b];
    if (a == b) continue;
    if (a > b) std::swap(a, b);
    if (!known({a, b})) out.pairs.emplace(a, b), ++out.bind_contacts;
  }
  const RegionLayout& layout = seg.layout;
  std::vector<uint32_t> regions_at(mesh.vertex_count(), 0);  // per welded position: a bit per region using it
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) regions_at[weld[mesh.indices[3 * t + k]]] |= 1u << seg.triangle_regions[t];
  std::vector<uint32_t> meets(size_t(layout.count()), 0);  // per region: the regions sharing a vertex with it
  for (uint32_t mask : regions_at)
    for (int k = 0; k < layout.count(); ++k)
      if (mask >> k & 1u) meets[size_t(k)] |= mask;
  for (size_t i = 0; i < spheres.size(); ++i)
    for (size_t j = i + 1; j < spheres.size(); ++j) {
      const FittedSphere& A = spheres[i];
      const FittedSphere& B = spheres[j];
      if (A.region == B.region || !layout.IsLimb(A.region) || !layout.IsLimb(B.region) ||
          !(meets[size_t(A.region)] >> int(B.region) & 1u))
        continue;
      const SpherePair p{uint16_t(i), uint16_t(j)};
      if ((A.center - B.center).norm() < 1.25 * (A.radius + B.radius) + near && !known(p))
        out.pairs.insert(p), ++out.creases;
    }
  return out;
}

}  // namespace

Result<BakeResult> Bake(const std::string& input_path, const BakeConfig& config, Context* ctx) {
  BakeResult r;
  if (!(config.crease_rel > 0.0 && config.crease_rel <= 0.5))  // NaN too
    return MakeError(Error::Code::kConfig, "crease_rel must be in (0, 0.5] (a fraction of the body height)");
  {
    // ImportMesh and FitSpheres time themselves ("import", "fit").
    auto mesh = ImportMesh(input_path, config.import, ctx);
    if (!mesh.ok()) return mesh.error();
    r.mesh = std::move(mesh).value();
    r.mesh_issues = InspectMesh(r.mesh);
  }
  {
    // The crease rule measures on the welded bind surface: how many pieces it has (a triangle soup with no
    // welded adjacency has one per triangle, and every fold of it counts as a contact).
    Context::Timer t(ctx, "crease");
    const std::vector<uint32_t> weld = ComputeWeldIds(r.mesh.positions);
    runtime::CreaseGraph graph;
    if (graph.Init(r.mesh.positions.data(), r.mesh.vertex_count(), r.mesh.indices.data(), r.mesh.triangle_count(),
                   weld.data(), 1.0f) == runtime::Status::kOk)
      r.crease_components = graph.components();
    if (ctx && r.crease_components > 1)
      ctx->Info("crease: the welded bind surface has " + std::to_string(r.crease_components) +
                " separate pieces (the crease is measured within each)");
  }
  const Mesh& mesh = r.mesh;
  {
    Context::Timer t(ctx, "segment");
    Result<Segmentation> seg = config.region_map.empty() ? Segment(mesh, config.segmentation, ctx)
                                                         : SegmentByMap(mesh, config.region_map, ctx);
    if (!seg.ok()) return seg.error();
    r.segmentation = std::move(seg).value();
  }
  if (config.compare_segmentations && config.region_map.empty() && mesh.skin && r.segmentation.layout.paper) {
    Context::Timer t(ctx, "segment_compare");
    const SegmentMethod other = r.segmentation.method == "rig" ? SegmentMethod::kGeometry : SegmentMethod::kRig;
    auto seg2 = Segment(mesh, other, ctx);
    if (seg2.ok()) {
      r.agreement = CompareSegmentations(mesh, r.segmentation, seg2.value());
      r.other_segmentation = std::move(seg2).value();
    } else {
      r.other_segmentation_error = seg2.error().message;
    }
  }
  {
    // "No silent wrong bake" (issue 11): the segmentation must look like a body before anything is fitted
    // to it (a refused body costs no fit). SEG-AGREE uses the rig/geometry agreement measured above —
    // rigged bodies only: a body with one segmentation source has nothing to compare with.
    Context::Timer t(ctx, "plausibility");
    r.plausibility = CheckPlausibility(mesh, r.segmentation, nullptr, r.agreement ? &*r.agreement : nullptr,
                                       config.plausibility);
    // With segmentation auto, a rigged body whose segmentation looks wrong tries its bone tree (the
    // any-skeleton path) before it is refused:
    // - a horizontal trunk is no standing body (a quadruped whose bones carry humanoid names): the bone tree's
    //   segmentation is taken and its own checks decide;
    // - any other failed check on the geometry segmentation (auto only falls back to geometry when the rig's
    //   bone names are not usable, e.g. joints named node0…node21): the bone tree's is taken only when it
    //   passes every check, otherwise the geometry's findings stand.
    const bool auto_rigged = config.segmentation == SegmentMethod::kAuto && config.region_map.empty() && mesh.skin &&
                             r.segmentation.layout.paper;
    const bool trunk_axis = HasFinding(r.plausibility, "PLAUS-TRUNK-AXIS");
    const bool unnamed_rig = r.segmentation.method == "geometry" && !r.plausibility.empty();
    if (auto_rigged && (trunk_axis || unnamed_rig)) {
      Result<Segmentation> skeleton = SegmentBySkeleton(mesh, {}, ctx);
      std::vector<PlausibilityFinding> checks;
      if (skeleton.ok()) checks = CheckPlausibility(mesh, skeleton.value(), nullptr, nullptr, config.plausibility);
      if (skeleton.ok() && (trunk_axis || checks.empty())) {
        std::string codes;
        for (const PlausibilityFinding& f : r.plausibility) codes += (codes.empty() ? "" : ", ") + f.code;
        const std::string why = trunk_axis ? "has a horizontal trunk (PLAUS-TRUNK-AXIS)"
                                           : "looks wrong (" + codes + ") and the rig's bone names are not usable";
        if (ctx)
          ctx->Info("segment: the " + r.segmentation.method + " segmentation " + why +
                    ": segmented " + (trunk_axis ? "as a creature " : "") + "by its skeleton instead");
        const std::string before = r.segmentation.method;
        r.segmentation = std::move(skeleton).value();
        r.segmentation.notes = "the " + before + " segmentation " + (trunk_axis ? "had a horizontal trunk (PLAUS-TRUNK-AXIS)" : why) +
                               "; " + r.segmentation.notes;
        r.agreement.reset();
        r.other_segmentation.reset();
        r.other_segmentation_error.clear();
        r.plausibility = std::move(checks);
      } else {
        const std::string failed = !skeleton.ok() ? skeleton.error().message : "its checks failed too";
        for (PlausibilityFinding& f : r.plausibility)
          if (f.code == "PLAUS-TRUNK-AXIS" || (!trunk_axis && &f == &r.plausibility.front()))
            f.message += "; the any-skeleton path failed too: " + failed;
      }
    }
    if (!r.segmentation.layout.paper && r.other_segmentation_error.empty())
      r.other_segmentation_error = "a creature's regions (the any-skeleton path) have no geometric counterpart to compare with";
    if (!r.plausibility.empty() && !config.force) return Refuse(mesh, r.plausibility);
  }
  // Head, hands and feet (issue 11, `regions: extended`, the cover fit only): cut from the five
  // regions the checks above accepted, each then a region with its own spheres and chains.
  if (config.regions == RegionSet::kExtended && config.fit.method == FitMethod::kCover &&
      r.segmentation.layout.IsPaperFive()) {
    Context::Timer t(ctx, "extremities");
    auto split = SplitExtremities(mesh, r.segmentation, ExtremityMethod::kAuto, ctx);
    if (!split.ok()) return split.error();
    if (Status s = ApplyExtremities(mesh, split.value(), &r.segmentation); !s.ok()) return s.error();
  }
  {
    auto fit = FitSpheres(mesh, r.segmentation, config.fit, ctx);
    if (!fit.ok()) return fit.error();
    r.fit = std::move(fit).value();
  }
  const auto& spheres = r.fit.spheres;
  if (spheres.size() > 0xFFFF) return MakeError(Error::Code::kFit, "more than 65,535 spheres");
  {
    Context::Timer t(ctx, "chains");
    // A creature keeps its own chains (every limb with the others and the trunk) unless the
    // configuration names chains other than Table 1's.
    const RegionLayout& layout = r.segmentation.layout;
    const bool table_one = IsTableOneChains(config.chains);
    const std::vector<ChainDef> defs = !table_one          ? config.chains
                                       : !layout.paper       ? CreatureChainDefs(layout)
                                       : layout.IsPaperFive() ? config.chains
                                                              : ExtendedChainDefs(layout);
    auto chains = BuildChains(spheres, defs, layout);
    if (!chains.ok()) return chains.error();
    r.chains = std::move(chains).value();
    if (config.fit.method == FitMethod::kPaper)
      r.excluded = ExcludedPairs(spheres, &r.cross_region_bind_overlaps);
    else
      r.excluded = BindExcludedPairs(spheres, (config.near_rel + 2.0 * config.contact_margin_rel) * r.fit.body_height,
                                     &r.exclusion_reasons,
                                     &r.cross_region_bind_overlaps, mesh.up_axis, layout.IsPaperFive() ? nullptr : &layout);
  }
  {
    Context::Timer t(ctx, "surrounding_regions");
    auto surr = BuildSurroundingRegions(mesh, r.segmentation, spheres,
                                        config.fit.method == FitMethod::kPaper ? Ownership::kNearestCentre
                                                                               : Ownership::kNearestSurface);
    if (!surr.ok()) return surr.error();
    r.surrounding = std::move(surr).value();
    r.unassigned_triangles = mesh.triangle_count() - r.surrounding.offsets.back();
    AddReachRegions(mesh, r.segmentation, spheres, config.reach_rel * r.fit.body_height, &r.surrounding);
  }
  if (!r.segmentation.layout.paper && config.fit.method == FitMethod::kCover) {
    Context::Timer t(ctx, "creature_exclusions");
    const double near = (config.near_rel + 2.0 * config.contact_margin_rel) * r.fit.body_height;
    auto extra = CreatureExcludedPairs(mesh, r.segmentation, spheres, r.surrounding, r.excluded, near);
    if (!extra.ok()) return extra.error();
    r.bind_contact_exclusions = extra->bind_contacts;
    r.limb_crease_exclusions = extra->creases;
    r.excluded.insert(r.excluded.end(), extra->pairs.begin(), extra->pairs.end());
    std::sort(r.excluded.begin(), r.excluded.end());
    if (ctx && !extra->pairs.empty())
      ctx->Info("exclusions (creature): " + std::to_string(extra->bind_contacts) +
                " sphere pair(s) whose triangles intersect at bind pose (" + std::to_string(extra->triangle_pairs) +
                " triangle pairs: the model passes through itself there), " + std::to_string(extra->creases) +
                " pair(s) of two limbs where they meet (a crease)");
  }
  {
    std::vector<std::vector<float>> poses;
    if (config.pivot_poses && mesh.skin) {
      Context::Timer tp(ctx, "pivot_poses");
      TrainingPoseOptions po;
      po.count = config.pivot_poses;
      po.max_angle_deg = float(config.pivot_pose_angle);
      poses = SampleTrainingPoses(mesh, po);
    }
    Context::Timer t(ctx, "pivots");
    PivotTraining training;
    training.poses = &poses;
    training.witness_reach = 0.02 * r.fit.body_height;
    auto piv = ChoosePivots(mesh, spheres, r.surrounding, &r.segmentation, poses.empty() ? nullptr : &training);
    if (!piv.ok()) return piv.error();
    r.pivots = std::move(piv).value();
    if (ctx && r.pivots.training.poses) {
      const Pivots::Training& pt = r.pivots.training;
      char line[200];
      std::snprintf(line, sizeof line,
                    "pivots: refined on %u random poses of the rig: %u of %zu spheres changed, tracking error "
                    "%.3f -> %.3f %% of the height",
                    pt.poses, pt.spheres_changed, spheres.size(), 100 * pt.error_before / r.fit.body_height,
                    100 * pt.error_after / r.fit.body_height);
      ctx->Info(line);
    } else if (ctx && config.pivot_poses && !mesh.skin) {
      ctx->Info("pivots: pivot_poses ignored: the mesh has no skin to pose");
    }
  }
  {
    Context::Timer t(ctx, "phi2_accuracy");
    AccuracyAccumulator all1, all1a, all2;
    r.phi2.resize(spheres.size());
    r.sphere_accuracy.resize(spheres.size());
    for (size_t s = 0; s < spheres.size(); ++s) {
      const std::vector<uint32_t> verts = r.surrounding.Vertices(mesh, s);
      std::vector<Eigen::Vector3d> pts;
      pts.reserve(verts.size());
      for (uint32_t v : verts)
        pts.emplace_back(mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2]);
      r.phi2[s] = MinimumEnclosingBall(pts);
      AccuracyAccumulator a1, a1a, a2;
      const FittedSphere& S = spheres[s];
      for (const Eigen::Vector3d& p : pts) {
        a1.Add(S.center_phi1, S.radius_phi1, p);
        a1a.Add(S.center, S.radius, p);
        a2.Add(r.phi2[s].center, r.phi2[s].radius, p);
        all1.Add(S.center_phi1, S.radius_phi1, p);
        all1a.Add(S.center, S.radius, p);
        all2.Add(r.phi2[s].center, r.phi2[s].radius, p);
      }
      r.sphere_accuracy[s] = {a1.Stats(), a1a.Stats(), a2.Stats()};
    }
    r.accuracy = {all1.Stats(), all1a.Stats(), all2.Stats()};
  }
  {
    // Bind-pose coverage and protrusion of the spheres the runtime refits (φ1'), for the report and
    // the asset; a mesh too open to measure gets a warning, not an error.
    std::vector<Ball> balls;
    for (const FittedSphere& s : spheres) balls.push_back({s.center, s.radius});
    auto cov = MeasureCoverage(mesh.positions, mesh.indices, balls, r.coverage_options, ctx);
    if (cov.ok()) r.coverage = cov.value();
    else if (ctx) ctx->Warn("coverage not measured: " + cov.error().message);
  }
  if (r.coverage) {
    // PLAUS-OUTSIDE: the spheres' volume outside the body (the other checks ran after segmentation).
    const size_t before = r.plausibility.size();
    CheckProtrusion(*r.coverage, config.plausibility, &r.plausibility);
    if (r.plausibility.size() > before && !config.force) return Refuse(mesh, r.plausibility);
  }
  if (ctx)
    for (const PlausibilityFinding& f : r.plausibility)
      ctx->Warn("plausibility check failed, written anyway (--force): " + f.code + ": " + f.message);
  if (mesh.skin) {
    // The joint refit's centre weights (schema v3): a rig without usable rows is a warning, not an error.
    uint32_t unweighted = 0;
    auto w = CentreSkinWeights(mesh, r.surrounding, r.pivots, &unweighted);
    if (!w.ok()) {
      if (ctx) ctx->Warn("no joint weights in the asset (refit from joint matrices unavailable): " + w.error().message);
    } else {
      r.centre_weights = std::move(w).value();
      if (unweighted && ctx)
        ctx->Warn(std::to_string(unweighted) + " sphere(s) have no skinned vertex in their surrounding region: "
                  "they follow joint 0 in the refit from joint matrices");
    }
  }
  {
    Context::Timer t(ctx, "write");
    AssetInputs in;
    in.mesh = &mesh;
    in.segmentation = &r.segmentation;
    in.fit = &r.fit;
    in.phi2 = &r.phi2;
    in.chains = &r.chains;
    in.excluded = &r.excluded;
    in.surrounding = &r.surrounding;
    in.pivots = &r.pivots;
    if (r.centre_weights) in.centre_weights = &*r.centre_weights;
    in.accuracy = r.accuracy;
    in.params = config.fit;
    const std::string canonical = CanonicalConfig(config, &r.segmentation.layout);
    in.config_hash = Hash64(canonical.data(), canonical.size());
    in.contact_margin = config.contact_margin_rel * r.fit.body_height;
    in.fold_margin = FoldMarginRel(config, r.segmentation.layout) * r.fit.body_height;
    in.bind_positions = &mesh.positions;
    in.crease = config.crease_rel * r.fit.body_height;
    in.skin_weights = config.skin_weights;
    if (r.coverage) in.coverage = &*r.coverage;
    in.coverage_voxel_rel = r.coverage_options.voxel_rel;
    in.forced_findings = &r.plausibility;
    r.asset = BuildAsset(in);
    // What the runtime refuses is never handed on (a writer bug would reach every game that loads it).
    std::vector<uint64_t> aligned((r.asset.size() + 7) / 8);
    std::memcpy(aligned.data(), r.asset.data(), r.asset.size());
    runtime::AssetView view;
    if (const runtime::Status s = runtime::LoadAsset(aligned.data(), r.asset.size(), &view); s != runtime::Status::kOk)
      return MakeError(Error::Code::kInternal, std::string("the baked asset does not load in the runtime (a baker bug): ") +
                                                   runtime::ToString(s));
  }
  return r;
}

// ---------------------------------------------------------------------------------------------------
// Report

namespace {

json StatsJson(const AccuracyStats& s) {
  return {{"mean_abs_F", s.mean_abs_f}, {"rms_F", s.rms_f}, {"min_F", s.min_f}, {"max_F", s.max_f}, {"count", s.count}};
}

std::string LabelString(uint8_t labels) {
  std::string s;
  if (labels & kLabelL) s += 'L';
  if (labels & kLabelR) s += 'R';
  if (labels & kLabelT) s += 'T';
  if (labels & kLabelD) s += 'D';
  return s;
}

}  // namespace

json MakeBakeReport(const BakeResult& r, const BakeConfig& config, const Context& ctx) {
  const Mesh& mesh = r.mesh;
  const auto& spheres = r.fit.spheres;
  json j;
  j["input"] = mesh.source_path;
  j["format"] = mesh.source_format;
  j["vertices"] = mesh.vertex_count();
  j["vertex_contract"] = mesh.vertex_contract;
  if (mesh.source_vertex_count || mesh.joined_vertex_count)
    j["vertices_by_contract"] = {{"source", mesh.source_vertex_count}, {"joined", mesh.joined_vertex_count}};
  j["triangles"] = mesh.triangle_count();
  j["spheres"] = spheres.size();
  j["units"] = mesh.units;
  j["body_height"] = r.fit.body_height;
  j["disk_step"] = r.fit.disk_step;
  j["asset_bytes"] = r.asset.size();
  json parts = json::array();
  for (const MeshPart& p : mesh.parts)
    parts.push_back({{"name", p.name}, {"first_vertex", p.first_vertex}, {"vertices", p.vertex_count},
                     {"first_triangle", p.first_triangle}, {"triangles", p.triangle_count}});
  j["parts"] = parts;

  json regions = json::object();
  const RegionLayout& layout = r.segmentation.layout;
  for (int k = 0; k < layout.count(); ++k) {
    const Region reg = static_cast<Region>(k);
    size_t tris = std::count(r.segmentation.triangle_regions.begin(), r.segmentation.triangle_regions.end(), uint8_t(k));
    size_t sph = std::count_if(spheres.begin(), spheres.end(), [&](const FittedSphere& s) { return s.region == reg; });
    json& e = regions[layout.Name(reg)];
    e = {{"symbol", RegionSymbol(reg)}, {"triangles", tris}, {"spheres", sph}};
    if (!layout.IsPaperFive()) {  // a creature's or the extended layout: what each region is (Asset.regions)
      const RegionInfo& info = layout.regions[size_t(k)];
      e["kind"] = info.kind == RegionKind::kTrunk ? "trunk" : "limb";
      if (!info.bone.empty()) e["bone"] = info.bone;
      if (info.mirror >= 0) e["mirror"] = layout.Name(Region(info.mirror));
      if (info.parent >= 0) e["parent"] = layout.Name(Region(info.parent));
    }
  }
  j["regions"] = regions;
  if (!layout.paper) j["body"] = "creature (any-skeleton path: limbs off the trunk, their own chains)";
  else if (!layout.IsPaperFive()) j["body"] = "standing biped, extended regions (head, hands, feet: Table 1's chains extended)";

  json seg = {{"method", r.segmentation.method}, {"notes", r.segmentation.notes}};
  if (r.agreement && r.other_segmentation) {
    json iou = json::object();
    for (int k = 0; k < kRegionCount; ++k) iou[RegionName(static_cast<Region>(k))] = r.agreement->iou[k];
    seg["compared_with"] = r.other_segmentation->method;
    seg["agreement"] = {{"triangle_fraction", r.agreement->triangle_fraction},
                        {"area_fraction", r.agreement->area_fraction}, {"iou", iou}};
  } else if (!r.other_segmentation_error.empty()) {
    seg["comparison_error"] = r.other_segmentation_error;
  }
  j["segmentation"] = seg;

  json chains = json::array();
  size_t total = 0;
  for (const Chain& c : r.chains) {
    chains.push_back({{"name", c.name}, {"spheres", c.spheres.size()}, {"members", c.spheres}});
    total += c.spheres.size();
  }
  j["chains"] = chains;
  j["mean_spheres_per_chain"] = r.chains.empty() ? 0.0 : double(total) / double(r.chains.size());
  j["fit"] = FitMethodName(config.fit.method);
  j["contact_margin"] = config.contact_margin_rel * r.fit.body_height;
  j["contact_margin_rel"] = config.contact_margin_rel;
  if (const double fold = FoldMarginRel(config, r.segmentation.layout); fold >= 0.0)
    j["fold_margin"] = fold * r.fit.body_height, j["fold_margin_rel"] = fold;
  j["crease"] = {{"crease", config.crease_rel * r.fit.body_height}, {"crease_rel", config.crease_rel},
                 {"surface_components", r.crease_components}};
  if (r.coverage)
    j["coverage"] = {{"coverage", r.coverage->coverage},
                     {"protrusion", r.coverage->protrusion},
                     {"outside_p95_rel", r.coverage->outside_p95_rel},
                     {"outside_max_rel", r.coverage->outside_max_rel},
                     {"voxel_rel", r.coverage_options.voxel_rel},
                     {"undecided_voxels", r.coverage->voxels_undecided},
                     {"skin_outside_p50_rel", r.coverage->skin_outside_p50_rel},
                     {"skin_outside_p95_rel", r.coverage->skin_outside_p95_rel},
                     {"skin_outside_max_rel", r.coverage->skin_outside_max_rel},
                     {"skin_within_share", r.coverage->skin_within_share}};
  j["excluded_pairs"] = r.excluded.size();
  if (config.fit.method == FitMethod::kPaper)
    j["exclusions"] = {{"rule", "paper: sequence neighbours up to 2 apart, torso levels up to 2 apart, bind overlap, "
                                "limb-torso junction within half the radii"}};
  else
    j["exclusions"] = {{"rule", "bind geometry: limb sequence neighbours, limb or torso spheres side by side, bind overlap, "
                                "within near_rel + 2 contact_margin_rel of the height, limb-torso pairs within 1.25 (rA + rB) + that, "
                                "two limbs' root spheres off one region within 1.25 (rA + rB) + that (the crotch), "
                                "trunk spheres within 1.25 (rA + rB) + that when the head is a region of its own (the belly's fold)"},
                       {"limb_neighbour", r.exclusion_reasons.limb_neighbour},
                       {"limb_side_by_side", r.exclusion_reasons.limb_side_by_side},
                       {"torso_side_by_side", r.exclusion_reasons.torso_side_by_side},
                       {"bind_overlap", r.exclusion_reasons.bind_overlap},
                       {"bind_near", r.exclusion_reasons.bind_near},
                       {"junction", r.exclusion_reasons.junction},
                       {"sibling_crease", r.exclusion_reasons.sibling_crease},
                       {"trunk_fold", r.exclusion_reasons.trunk_fold},
                       {"bind_contact", r.bind_contact_exclusions},
                       {"limb_crease", r.limb_crease_exclusions}};
  if (!r.cross_region_bind_overlaps.empty()) {
    json w = json::array();
    for (const SpherePair& p : r.cross_region_bind_overlaps) w.push_back({p.first, p.second});
    j["warnings"]["cross_region_bind_overlaps"] = w;
  }
  j["unassigned_triangles"] = r.unassigned_triangles;
  if (!r.surrounding.reach_offsets.empty() && r.mesh.triangle_count() > 0)
    j["reach_regions"] = {{"reach_rel", config.reach_rel},
                          {"spheres_per_triangle", double(r.surrounding.reach_triangles.size()) / r.mesh.triangle_count()}};
  j["mesh_issues"] = {{"degenerate_triangles", r.mesh_issues.degenerate_triangles},
                      {"non_manifold_edges", r.mesh_issues.non_manifold_edges}};
  j["accuracy"] = {{"phi1", StatsJson(r.accuracy.phi1)},
                   {"phi1_adjusted", StatsJson(r.accuracy.phi1_adjusted)},
                   {"phi2", StatsJson(r.accuracy.phi2)}};
  json per = json::array();
  for (size_t s = 0; s < spheres.size(); ++s) {
    const FittedSphere& S = spheres[s];
    per.push_back({{"index", s},
                   {"region", RegionSymbol(S.region)},
                   {"labels", LabelString(S.labels)},
                   {"sequence", S.sequence},
                   {"level", S.level},
                   {"center", {S.center.x(), S.center.y(), S.center.z()}},
                   {"radius", S.radius},
                   {"radius_phi1", S.radius_phi1},
                   {"radius_phi2", r.phi2[s].radius},
                   {"surrounding_triangles", r.surrounding.offsets[s + 1] - r.surrounding.offsets[s]},
                   {"mean_abs_F", {{"phi1", r.sphere_accuracy[s].phi1.mean_abs_f},
                                   {"phi1_adjusted", r.sphere_accuracy[s].phi1_adjusted.mean_abs_f},
                                   {"phi2", r.sphere_accuracy[s].phi2.mean_abs_f}}}});
  }
  if (r.centre_weights) {
    const CentreWeights& cw = *r.centre_weights;
    for (size_t s = 0; s < spheres.size(); ++s) {
      json inf = json::array();
      for (size_t k = 0; k < 4; ++k)
        if (cw.weights[4 * s + k] > 0.0f) {
          const uint16_t jt = cw.joints[4 * s + k];
          const int32_t node = r.mesh.skin->joints[jt].node;
          const std::string name = node >= 0 && size_t(node) < r.mesh.skin->nodes.size()
                                       ? r.mesh.skin->nodes[size_t(node)].name : std::string();
          inf.push_back({{"joint", jt}, {"name", name}, {"weight", cw.weights[4 * s + k]}});
        }
      per[s]["centre_joints"] = inf;
    }
    j["joint_refit"] = {{"joints", cw.joint_count},
                        {"derivation", "per sphere: mean skin weights of its surrounding-region vertices, the four "
                                       "largest kept and renormalised; radius = bind radius"}};
  }
  j["sphere_table"] = per;
  if (r.pivots.training.poses)
    j["pivot_training"] = {{"poses", r.pivots.training.poses},
                           {"max_angle_deg", config.pivot_pose_angle},
                           {"spheres_changed", r.pivots.training.spheres_changed},
                           {"tracking_error_before_rel", r.pivots.training.error_before / r.fit.body_height},
                           {"tracking_error_after_rel", r.pivots.training.error_after / r.fit.body_height}};
  json plaus = json::array();
  for (const PlausibilityFinding& f : r.plausibility)
    plaus.push_back({{"code", f.code}, {"severity", "error"}, {"message", f.message}});
  // Every check passed, or (forced) the failed ones: a refused bake writes no report.
  j["plausibility"] = {{"passed", r.plausibility.empty()}, {"forced", config.force && !r.plausibility.empty()},
                       {"errors", plaus}};
  j["params"] = json::parse(CanonicalConfig(config, &r.segmentation.layout));
  json timings = json::object();
  double sum = 0;
  for (const auto& [name, ms] : ctx.timings_ms) {
    timings[name] = ms;
    if (name.find('.') == std::string::npos) sum += ms;  // "a.b" is a sub-stage of "a"
  }
  timings["total"] = sum;
  j["timings_ms"] = timings;
  return j;
}

std::string TorsoRayCsv(const BakeResult& r) {
  std::ostringstream out;
  out << "sphere,labels,ray,dir_x,dir_y,dir_z,surface,phi1,phi1_adjusted,phi2\n";
  // Where the ray o + t·d (t ≥ 0) leaves the sphere (c, r): the larger root of |o + t d − c|² = r²;
  // empty when the ray misses the sphere.
  auto exit_distance = [](const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& c,
                          double rad) -> std::string {
    const Eigen::Vector3d oc = o - c;
    const double b = oc.dot(d), cc = oc.squaredNorm() - rad * rad;
    const double disc = b * b - cc;
    if (disc < 0) return "";
    const double t = -b + std::sqrt(disc);
    if (t < 0) return "";
    std::ostringstream s;
    s << t;
    return s.str();
  };
  auto surface = [](double hit) -> std::string {
    if (!std::isfinite(hit)) return "";  // the ray left through an opening (arm, leg)
    std::ostringstream s;
    s << hit;
    return s.str();
  };
  const auto& spheres = r.fit.spheres;
  for (size_t s = 0; s < spheres.size(); ++s) {
    const FittedSphere& S = spheres[s];
    if (S.region != Region::kTorso) continue;
    for (size_t k = 0; k < S.ray_ids.size() && k < S.ray_dirs.size() && k < S.ray_hit.size(); ++k) {
      const Eigen::Vector3d& d = S.ray_dirs[k];
      out << s << ',' << LabelString(S.labels) << ',' << S.ray_ids[k] << ',' << d.x() << ',' << d.y() << ','
          << d.z() << ',' << surface(S.ray_hit[k]) << ',' << exit_distance(S.disk_center, d, S.center_phi1, S.radius_phi1)
          << ',' << exit_distance(S.disk_center, d, S.center, S.radius) << ','
          << exit_distance(S.disk_center, d, r.phi2[s].center, r.phi2[s].radius) << '\n';
    }
  }
  return out.str();
}

}  // namespace spherechain::baker
