// spherechain baker — sphere fitting of all five regions (paper §3): the four tubular regions by the
// moving circumference (fit_tubular.cpp), the torso by the ray disk (fit_torso.cpp).
#include <exception>
#include <string>

#include "geometry.h"
#include "spherechain/baker/fit.h"
#include "segment_internal.h"

namespace spherechain::baker {

const char* FitMethodName(FitMethod m) { return m == FitMethod::kPaper ? "paper" : "cover"; }

Result<FitResult> FitSpheres(const Mesh& mesh, const Segmentation& seg, const FitParams& params, Context* ctx) {
  Context::Timer timer(ctx, "fit");
  if (seg.triangle_regions.size() != mesh.triangle_count())
    return MakeError(Error::Code::kFit, "fit: segmentation has " + std::to_string(seg.triangle_regions.size()) +
                                            " triangle regions for " + std::to_string(mesh.triangle_count()) +
                                            " triangles");
  if (params.method == FitMethod::kPaper && !seg.layout.paper)
    return MakeError(Error::Code::kFit, "fit: the paper fit (\"fit\": \"paper\") needs the paper's five regions of a "
                                        "standing body; a creature's " + std::to_string(seg.layout.count()) +
                                        " regions (segmentation " + seg.method + ") take the cover fit (\"fit\": \"cover\")");
  try {
    std::vector<std::vector<uint32_t>> tris(kRegionCount);
    for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
      const uint8_t r = seg.triangle_regions[t];
      if (r < kRegionCount) tris[r].push_back(t);
    }
    // Fit on the welded connectivity: meshes whose vertices are split at seams (or not shared at all,
    // as assimp gives .X files one vertex per face corner) still form connected limbs. Representatives
    // are source vertex indices, so everything the fit returns refers to the source mesh.
    Mesh welded_storage;
    const Mesh* fit_mesh = &mesh;
    {
      const segment_detail::WeldedGraph graph = segment_detail::BuildWeldedGraph(mesh);
      bool any = false;
      for (uint32_t v = 0; v < mesh.vertex_count() && !any; ++v) any = graph.rep[v] != v;
      if (any) {
        welded_storage.positions = mesh.positions;
        welded_storage.up_axis = mesh.up_axis;
        welded_storage.indices.resize(mesh.indices.size());
        for (size_t i = 0; i < mesh.indices.size(); ++i) welded_storage.indices[i] = graph.rep[mesh.indices[i]];
        fit_mesh = &welded_storage;
      }
    }
    FitResult result;
    result.body_height = fit_detail::BodyHeight(mesh, fit_detail::UpVector(mesh.up_axis));
    result.disk_step = fit_detail::DiskStep(mesh, params);
    if (params.method == FitMethod::kCover) {
      auto cover = FitCover(*fit_mesh, seg, params, ctx);
      if (!cover.ok()) return cover.error();
      result.spheres = std::move(cover).value();
      if (ctx) ctx->Info("fit: " + std::to_string(result.spheres.size()) + " spheres (cover)");
      return result;
    }
    for (int r = 0; r < kRegionCount - 1; ++r) {
      const Region region = static_cast<Region>(r);
      auto limb = FitTubular(*fit_mesh, tris[r], region, params, ctx);
      if (!limb.ok()) return limb.error();
      for (FittedSphere& s : limb.value()) {
        s.center_phi2 = s.center;
        s.radius_phi2 = s.radius;
        result.spheres.push_back(std::move(s));
      }
    }
    auto torso = FitTorso(*fit_mesh, tris[static_cast<int>(Region::kTorso)], seg, params, ctx);
    if (!torso.ok()) return torso.error();
    for (FittedSphere& s : torso.value()) result.spheres.push_back(std::move(s));
    if (ctx) ctx->Info("fit: " + std::to_string(result.spheres.size()) + " spheres");
    return result;
  } catch (const std::exception& e) {
    return MakeError(Error::Code::kFit, std::string("fit: ") + e.what());
  }
}

}  // namespace spherechain::baker
