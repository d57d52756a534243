// spherechain baker — segmentation into the paper's five regions (§3, Figure 1).
#pragma once

#include <string>
#include <vector>

#include "spherechain/baker/types.h"

namespace spherechain::baker {

struct Segmentation {
  std::vector<uint8_t> triangle_regions;  ///< #T, Region value per triangle (never kNoRegion on success)
  std::vector<uint8_t> vertex_regions;    ///< #V, Region per vertex (kNoRegion for unreferenced vertices)
  std::string method;                     ///< "rig", "geometry" or "map"
  std::string notes;                      ///< human-readable diagnostics (pose found, cut heights, ...)
};

enum class SegmentMethod : uint8_t { kAuto, kRig, kGeometry };

/// Segments from skin weights and bone-name rules (arm/hand/finger/clavicle → arm? see segment_rig.cpp;
/// side from `.L`/`_L`/`Left`/...; legs from thigh/leg/knee/foot/toe; everything else torso).
/// Each limb region is then reduced to its largest connected piece (the rest joins the torso).
/// Errors: kSegmentation when the mesh has no skin or a limb's bones cannot be found.
Result<Segmentation> SegmentByRig(const Mesh& mesh, Context* ctx = nullptr);

/// Segments a standing body (A-pose, T-pose or arms-down) with no rig, from geometry alone.
/// `up` is the standing direction. Errors: kSegmentation "not a standing body: ..." when two legs and
/// two arms cannot be found.
Result<Segmentation> SegmentByGeometry(const Mesh& mesh, Context* ctx = nullptr);

/// Reads a user region map: a JSON file {"triangle_regions": [r0, r1, ...]} with #T values 0..4, or
/// {"vertex_regions": [...]} with #V values (a triangle takes its vertices' majority).
/// Errors: kIo, kConfig (wrong length, value out of range).
Result<Segmentation> SegmentByMap(const Mesh& mesh, const std::string& map_path, Context* ctx = nullptr);

/// kAuto: rig when the mesh has a skin whose bones are recognised, else geometry.
Result<Segmentation> Segment(const Mesh& mesh, SegmentMethod method, Context* ctx = nullptr);

/// Fraction of triangles (area-weighted) on which two segmentations agree, overall and per region
/// (IoU per region). Both must have the same triangle count.
struct SegmentationAgreement {
  double triangle_fraction = 0.0;            ///< agreeing triangles / #T
  double area_fraction = 0.0;                ///< agreeing area / total area
  std::array<double, kRegionCount> iou{};    ///< per region: |A∩B| / |A∪B| by triangle count
};
SegmentationAgreement CompareSegmentations(const Mesh& mesh, const Segmentation& a, const Segmentation& b);

}  // namespace spherechain::baker
