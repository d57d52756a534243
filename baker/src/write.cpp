#include "spherechain/baker/write.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <fstream>
#include <system_error>

#include <unistd.h>

#include <flatbuffers/flatbuffers.h>

#include "spherechain/runtime/asset.h"

#include "spherechain/runtime/schema/spherechain_generated.h"

namespace spherechain::baker {

namespace fb = spherechain::schema;


namespace {

fb::Sphere ToSphere(const Eigen::Vector3d& c, double r) {
  return fb::Sphere(fb::Vec3(float(c.x()), float(c.y()), float(c.z())), float(r));
}

flatbuffers::Offset<fb::AccuracyStats> ToStats(flatbuffers::FlatBufferBuilder& b, const AccuracyStats& s) {
  return fb::CreateAccuracyStats(b, float(s.mean_abs_f), float(s.rms_f), float(s.min_f), float(s.max_f));
}

fb::UpAxis ToUpAxis(UpAxis a) {
  switch (a) {
    case UpAxis::kZ: return fb::UpAxis::Z;
    case UpAxis::kX: return fb::UpAxis::X;
    case UpAxis::kY: break;
  }
  return fb::UpAxis::Y;
}

// Asset.skin_counts / skin_joints / skin_weights from the imported rows (weights summing to 1): the
// influences above 0, each weight × 255 rounded down and the remainder of 255 handed out by largest
// fractions, so every weight stays within 1/255 of its value and a vertex's sum to 255. A vertex with more
// than 255 influences (or none) gets count 0: its patch is never culled (dropping influences would make the
// runtime's bound wrong). Joints < 65,536 (CentreSkinWeights refuses more).
void SkinRows(const Skin& skin, std::vector<uint8_t>* counts, std::vector<uint16_t>* joints,
              std::vector<uint8_t>* weights) {
  const size_t V = skin.weight_offsets.size() - 1;
  counts->assign(V, 0);
  std::vector<std::pair<float, uint32_t>> row;
  std::vector<uint32_t> q;
  std::vector<std::pair<double, size_t>> frac;
  for (size_t v = 0; v < V; ++v) {
    row.clear();
    for (uint32_t e = skin.weight_offsets[v]; e < skin.weight_offsets[v + 1]; ++e)
      if (skin.weights[e] > 0.0f) row.emplace_back(skin.weights[e], skin.weight_joints[e]);
    std::sort(row.begin(), row.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    double sum = 0.0;
    for (const auto& r : row) sum += r.first;
    if (row.empty() || row.size() > 255 || !(sum > 0.0)) continue;
    q.assign(row.size(), 0);
    frac.clear();
    uint32_t given = 0;
    for (size_t k = 0; k < row.size(); ++k) {
      const double x = row[k].first / sum * 255.0;
      q[k] = uint32_t(std::floor(x));
      given += q[k];
      frac.emplace_back(x - q[k], k);
    }
    std::stable_sort(frac.begin(), frac.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    for (size_t k = 0; given < 255 && k < frac.size(); ++k, ++given) ++q[frac[k].second];
    (*counts)[v] = uint8_t(row.size());
    for (size_t k = 0; k < row.size(); ++k) joints->push_back(uint16_t(row[k].second)), weights->push_back(uint8_t(q[k]));
  }
}

}  // namespace

std::vector<uint8_t> BuildAsset(const AssetInputs& in) {
  const Mesh& mesh = *in.mesh;
  const auto& spheres = in.fit->spheres;
  flatbuffers::FlatBufferBuilder b(1 << 20);
  b.ForceDefaults(true);  // every scalar present: readers never see a missing field

  const Fingerprint fp = ComputeFingerprint(mesh);
  auto fingerprint = fb::CreateFingerprint(b, fp.vertex_count, fp.triangle_count, fp.positions_hash, fp.indices_hash);

  std::vector<flatbuffers::Offset<fb::MeshPart>> parts;
  for (const MeshPart& p : mesh.parts)
    parts.push_back(fb::CreateMeshPart(b, b.CreateString(p.name), p.first_vertex, p.vertex_count, p.first_triangle,
                                       p.triangle_count));
  auto parts_v = b.CreateVector(parts);

  auto params = fb::CreateBakeParams(b, uint32_t(in.params.rays), uint32_t(in.params.spheres_per_level),
                                     float(in.fit->disk_step), float(in.params.penetration_depth), 4u,
                                     b.CreateString(in.segmentation->method), in.config_hash);

  std::vector<fb::Sphere> s_adj, s_phi1, s_phi2;
  std::vector<uint8_t> regions, labels;
  for (size_t i = 0; i < spheres.size(); ++i) {
    s_adj.push_back(ToSphere(spheres[i].center, spheres[i].radius));
    s_phi1.push_back(ToSphere(spheres[i].center_phi1, spheres[i].radius_phi1));
    s_phi2.push_back(ToSphere((*in.phi2)[i].center, (*in.phi2)[i].radius));
    regions.push_back(static_cast<uint8_t>(spheres[i].region));
    labels.push_back(spheres[i].labels);
  }
  auto s_adj_v = b.CreateVectorOfStructs(s_adj);
  auto s_phi1_v = b.CreateVectorOfStructs(s_phi1);
  auto s_phi2_v = b.CreateVectorOfStructs(s_phi2);
  auto regions_v = b.CreateVector(regions);
  auto labels_v = b.CreateVector(labels);

  std::vector<flatbuffers::Offset<fb::Chain>> chains;
  for (const Chain& c : *in.chains) chains.push_back(fb::CreateChain(b, b.CreateString(c.name), b.CreateVector(c.spheres)));
  auto chains_v = b.CreateVector(chains);

  std::vector<fb::SpherePair> excluded;
  for (const SpherePair& p : *in.excluded) excluded.emplace_back(p.first, p.second);
  auto excluded_v = b.CreateVectorOfStructs(excluded);

  auto tri_regions_v = b.CreateVector(in.segmentation->triangle_regions);
  auto tri_spheres_v = b.CreateVector(in.surrounding->triangle_spheres);
  auto offsets_v = b.CreateVector(in.surrounding->offsets);
  auto surr_v = b.CreateVector(in.surrounding->triangles);
  flatbuffers::Offset<flatbuffers::Vector<uint32_t>> reach_off_v, reach_tri_v;
  if (!in.surrounding->reach_offsets.empty()) {
    reach_off_v = b.CreateVector(in.surrounding->reach_offsets);
    reach_tri_v = b.CreateVector(in.surrounding->reach_triangles);
  }
  auto piv_t_v = b.CreateVector(in.pivots->triangles);
  auto piv_v_v = b.CreateVector(in.pivots->vertices);
  std::vector<fb::PivotFrame> frames;
  for (const Pivots::Frame& f : in.pivots->frames)
    frames.emplace_back(fb::Vec3(f.local_center[0], f.local_center[1], f.local_center[2]),
                        fb::Vec3(f.centroid_offset[0], f.centroid_offset[1], f.centroid_offset[2]), f.mean_distance);
  auto frames_v = b.CreateVectorOfStructs(frames);
  auto triangles_v = b.CreateVector(mesh.indices);
  auto weld_v = b.CreateVector(ComputeWeldIds(mesh.positions));

  auto accuracy = fb::CreateAccuracy(b, ToStats(b, in.accuracy.phi1), ToStats(b, in.accuracy.phi1_adjusted),
                                     ToStats(b, in.accuracy.phi2));
  auto generator = b.CreateString(kGenerator);
  auto fit_method = b.CreateString(FitMethodName(in.params.method));
  flatbuffers::Offset<fb::Coverage> coverage = 0;
  if (in.coverage)
    coverage = fb::CreateCoverage(b, float(in.coverage->coverage), float(in.coverage->protrusion),
                                  float(in.coverage->outside_p95_rel), float(in.coverage->outside_max_rel),
                                  in.coverage_voxel_rel);
  auto units = b.CreateString(mesh.units);
  auto vertex_contract = b.CreateString(mesh.vertex_contract);
  flatbuffers::Offset<flatbuffers::Vector<uint16_t>> sphere_joints_v;
  flatbuffers::Offset<flatbuffers::Vector<float>> sphere_weights_v;
  if (in.centre_weights) {
    sphere_joints_v = b.CreateVector(in.centre_weights->joints);
    sphere_weights_v = b.CreateVector(in.centre_weights->weights);
  }

  flatbuffers::Offset<flatbuffers::Vector<flatbuffers::Offset<fb::BakeFinding>>> forced_v;
  const bool forced = in.forced_findings && !in.forced_findings->empty();
  if (forced) {
    std::vector<flatbuffers::Offset<fb::BakeFinding>> list;
    for (const PlausibilityFinding& f : *in.forced_findings)
      list.push_back(fb::CreateBakeFinding(b, b.CreateString(f.code), b.CreateString(f.message)));
    forced_v = b.CreateVector(list);
  }

  // A creature's regions or the extended layout (schema v4): the only reason to write v4 — a body of the
  // paper's five regions stays v3, readable by v3 SDKs and byte-identical to what they baked.
  const RegionLayout& layout = in.segmentation->layout;
  flatbuffers::Offset<flatbuffers::Vector<flatbuffers::Offset<fb::RegionInfo>>> regions_table;
  if (!layout.IsPaperFive()) {
    std::vector<flatbuffers::Offset<fb::RegionInfo>> list;
    for (const RegionInfo& r : layout.regions)
      list.push_back(fb::CreateRegionInfo(b, b.CreateString(r.name),
                                          r.kind == RegionKind::kTrunk ? fb::RegionKind::Trunk : fb::RegionKind::Limb,
                                          int16_t(r.mirror), b.CreateString(r.bone), int16_t(r.parent)));
    regions_table = b.CreateVector(list);
  }

  flatbuffers::Offset<flatbuffers::Vector<float>> bind_v;
  if (in.bind_positions && in.crease > 0.0) bind_v = b.CreateVector(*in.bind_positions);
  // The skin weights per vertex (schema v4, with the crease rule and the joint refit's weights): every
  // influence above 0, its weight rounded to 1/255 so that a vertex's sum to 255 (largest remainders).
  flatbuffers::Offset<flatbuffers::Vector<uint8_t>> skin_counts_v, skin_weights_v;
  flatbuffers::Offset<flatbuffers::Vector<uint16_t>> skin_joints_v;
  const bool skin_rows = in.skin_weights && in.bind_positions && in.crease > 0.0 && in.centre_weights && mesh.skin &&
                         mesh.skin->weight_offsets.size() == mesh.positions.size() / 3 + 1;
  if (skin_rows) {
    std::vector<uint8_t> counts, weights;
    std::vector<uint16_t> joints;
    SkinRows(*mesh.skin, &counts, &joints, &weights);
    skin_counts_v = b.CreateVector(counts);
    skin_joints_v = b.CreateVector(joints);
    skin_weights_v = b.CreateVector(weights);
  }

  fb::AssetBuilder ab(b);
  ab.add_schema_version(layout.IsPaperFive() ? spherechain::runtime::kPaperSchemaVersion : spherechain::runtime::kSchemaVersion);
  ab.add_generator(generator);
  ab.add_contact_margin(float(in.contact_margin));
  if (in.fold_margin >= 0.0) ab.add_fold_margin(float(in.fold_margin));
  if (in.bind_positions && in.crease > 0.0) ab.add_bind_positions(bind_v), ab.add_crease(float(in.crease));
  if (skin_rows) ab.add_skin_counts(skin_counts_v), ab.add_skin_joints(skin_joints_v), ab.add_skin_weights(skin_weights_v);
  ab.add_fit_method(fit_method);
  if (in.coverage) ab.add_coverage(coverage);
  if (in.centre_weights) {
    ab.add_joint_count(in.centre_weights->joint_count);
    ab.add_sphere_joints(sphere_joints_v);
    ab.add_sphere_joint_weights(sphere_weights_v);
  }
  ab.add_vertex_contract(vertex_contract);
  ab.add_source_vertex_count(mesh.source_vertex_count);
  ab.add_joined_vertex_count(mesh.joined_vertex_count);
  if (forced) ab.add_forced_findings(forced_v);
  if (!layout.IsPaperFive()) ab.add_regions(regions_table);
  if (!layout.IsPaperFive() && layout.paper) ab.add_biped(true);
  ab.add_fingerprint(fingerprint);
  ab.add_parts(parts_v);
  ab.add_units(units);
  ab.add_unit_scale_m(mesh.unit_scale_m);
  ab.add_up_axis(ToUpAxis(mesh.up_axis));
  ab.add_params(params);
  ab.add_spheres(s_adj_v);
  ab.add_spheres_phi1(s_phi1_v);
  ab.add_spheres_phi2(s_phi2_v);
  ab.add_sphere_regions(regions_v);
  ab.add_sphere_labels(labels_v);
  ab.add_chains(chains_v);
  ab.add_excluded_pairs(excluded_v);
  ab.add_triangle_regions(tri_regions_v);
  ab.add_triangle_spheres(tri_spheres_v);
  ab.add_surrounding_offsets(offsets_v);
  ab.add_surrounding_triangles(surr_v);
  if (!reach_off_v.IsNull()) ab.add_reach_offsets(reach_off_v), ab.add_reach_triangles(reach_tri_v);
  ab.add_pivot_triangles(piv_t_v);
  ab.add_pivot_vertices(piv_v_v);
  ab.add_pivot_frames(frames_v);
  ab.add_accuracy(accuracy);
  ab.add_triangles(triangles_v);
  ab.add_weld_ids(weld_v);
  fb::FinishAssetBuffer(b, ab.Finish());
  return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
}

}  // namespace spherechain::baker
