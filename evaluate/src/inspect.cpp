// spherechain evaluate — what an asset holds, as JSON (inspect.h).
#include "spherechain/evaluate/inspect.h"

#include <algorithm>
#include <cstdio>
#include <vector>

namespace spherechain::evaluate {

nlohmann::json DescribeAsset(const runtime::AssetView& v) {
  const schema::Asset& a = *v.asset;
  nlohmann::json j;
  j["schema_version"] = a.schema_version();
  j["generator"] = a.generator() ? a.generator()->str() : "";
  j["vertices"] = v.vertex_count;
  j["triangles"] = v.triangle_count;
  // The vertex contract (import.h VertexContract; "unrecorded": baked before the field).
  j["vertex_contract"] = a.vertex_contract() ? a.vertex_contract()->str() : "unrecorded";
  if (a.source_vertex_count() || a.joined_vertex_count())
    j["vertices_by_contract"] = {{"source", a.source_vertex_count()}, {"joined", a.joined_vertex_count()}};
  j["spheres"] = v.sphere_count;
  j["units"] = a.units() ? a.units()->str() : "";
  j["unit_scale_m"] = a.unit_scale_m();
  j["up_axis"] = schema::EnumNameUpAxis(a.up_axis());
  char hash[40];
  std::snprintf(hash, sizeof hash, "%016llx", (unsigned long long)a.fingerprint()->positions_hash());
  j["fingerprint"]["positions_hash"] = hash;
  std::snprintf(hash, sizeof hash, "%016llx", (unsigned long long)a.fingerprint()->indices_hash());
  j["fingerprint"]["indices_hash"] = hash;
  nlohmann::json parts = nlohmann::json::array();
  if (a.parts())
    for (const auto* p : *a.parts())
      parts.push_back({{"name", p->name() ? p->name()->str() : ""}, {"first_vertex", p->first_vertex()},
                       {"vertices", p->vertex_count()}, {"first_triangle", p->first_triangle()},
                       {"triangles", p->triangle_count()}});
  j["parts"] = parts;
  // The paper's five regions, or (schema v4) the creature's that Asset.regions names.
  const uint32_t R = runtime::RegionCount(v);
  std::vector<size_t> tris(R, 0), sph(R, 0);
  if (const auto* tr = a.triangle_regions())  // optional in the schema: counted when present
    for (uint8_t r : *tr)
      if (r < R) ++tris[r];
  if (const auto* sr = a.sphere_regions())
    for (uint8_t r : *sr)
      if (r < R) ++sph[r];
  for (uint32_t k = 0; k < R; ++k) {
    nlohmann::json& e = j["regions"][runtime::RegionName(v, k)];
    e = {{"triangles", tris[k]}, {"spheres", sph[k]}};
    if (const auto* regions = a.regions()) {
      const auto* info = regions->Get(k);
      e["symbol"] = "R" + std::to_string(k);
      e["kind"] = info->kind() == schema::RegionKind::Trunk ? "trunk" : "limb";
      e["bone"] = info->bone() ? info->bone()->str() : "";
      if (info->mirror() >= 0 && uint32_t(info->mirror()) < R) e["mirror"] = runtime::RegionName(v, uint32_t(info->mirror()));
    }
  }
  if (a.regions()) j["body"] = a.biped() ? "biped (extended layout: head, hands and feet)" : "creature (any-skeleton path)";
  nlohmann::json chains = nlohmann::json::array();
  size_t total = 0;
  for (const auto* c : *a.chains()) {
    chains.push_back({{"name", c->name() ? c->name()->str() : ""}, {"spheres", c->spheres()->size()}});
    total += c->spheres()->size();
  }
  j["chains"] = chains;
  j["mean_spheres_per_chain"] = chains.empty() ? 0.0 : double(total) / double(chains.size());
  j["excluded_pairs"] = a.excluded_pairs() ? a.excluded_pairs()->size() : 0;
  // Schema v3: the refit from joint matrices (0 joints: not available — older schema or no skin).
  j["joint_refit"] = {{"available", a.sphere_joints() != nullptr}, {"joints", a.sphere_joints() ? a.joint_count() : 0}};
  // Schema v4: the skin's own contact definition (the crease rule) and the skin weights for its joint-matrix
  // cull; an asset without them runs the narrow phase's exclusion-based definition only.
  j["skin_contacts"] = {{"crease", a.crease() > 0.0f ? nlohmann::json(a.crease()) : nlohmann::json(nullptr)},
                        {"skin_weights", a.skin_counts() != nullptr}};
  {  // triangles in no surrounding region (counted, not subtracted: the loader does not require the regions to
     // partition the triangles, and a hand-made asset may list one twice)
    std::vector<uint8_t> owned(v.triangle_count, 0);
    if (const auto* st = a.surrounding_triangles())
      for (uint32_t t : *st)
        if (t < v.triangle_count) owned[t] = 1;
    j["unassigned_triangles"] = size_t(std::count(owned.begin(), owned.end(), uint8_t{0}));
  }
  // Reach regions (absent before them): how many spheres a triangle stands behind, on average.
  j["reach_spheres_per_triangle"] =
      a.reach_triangles() && v.triangle_count ? nlohmann::json(double(a.reach_triangles()->size()) / v.triangle_count)
                                              : nlohmann::json(nullptr);
  if (const auto* p = a.params())
    j["params"] = {{"rays", p->rays()}, {"spheres_per_level", p->spheres_per_level()}, {"disk_step", p->disk_step()},
                   {"penetration_depth", p->penetration_depth()}, {"pivots_per_sphere", p->pivots_per_sphere()},
                   {"segmentation", p->segmentation() ? p->segmentation()->str() : ""}};
  auto stats = [](const schema::AccuracyStats* s) -> nlohmann::json {
    if (!s) return nullptr;
    return {{"mean_abs_F", s->mean_abs_f()}, {"rms_F", s->rms_f()}, {"min_F", s->min_f()}, {"max_F", s->max_f()}};
  };
  if (const auto* acc = a.accuracy())
    j["accuracy"] = {{"phi1", stats(acc->phi1())}, {"phi1_adjusted", stats(acc->phi1_adjusted())},
                     {"phi2", stats(acc->phi2())}};
  // Schema v2: the fit, the contact margin and the bake's bind-pose coverage measure.
  j["fit"] = a.fit_method() ? a.fit_method()->str() : "paper";
  j["contact_margin"] = a.contact_margin();
  j["fold_margin"] = a.fold_margin() >= 0.0f ? nlohmann::json(a.fold_margin()) : nlohmann::json(nullptr);
  if (const auto* c = a.coverage())
    j["coverage"] = {{"coverage", c->coverage()},
                     {"protrusion", c->protrusion()},
                     {"outside_p95_rel", c->outside_p95_rel()},
                     {"outside_max_rel", c->outside_max_rel()},
                     {"voxel_rel", c->voxel_rel()}};
  // Plausibility checks the bake failed and was forced past (bake --force; validate reports them as errors).
  nlohmann::json forced = nlohmann::json::array();
  if (const auto* f = a.forced_findings())
    for (const auto* x : *f)
      forced.push_back({{"code", x->code() ? x->code()->str() : ""}, {"message", x->message() ? x->message()->str() : ""}});
  j["forced_findings"] = forced;
  return j;
}

}  // namespace spherechain::evaluate
