// spherechain baker — segmentation from skin weights and bone-name rules (paper §3 regions R0..R4).
//
// Each bone is given a region by its name (RegionOfBone). Decision: clavicle / shoulder / collar /
// scapula bones belong to the TORSO — the paper's arm is a tube cut at the armpit, and the shoulder cap
// they skin moves with the trunk; likewise MakeHuman's `pelvis.L/.R` (hip flesh) is torso while a sided
// `hip` (BCN `B_Hip_Left`, i.e. the thigh joint) is leg. A vertex sums its weights per region; a
// triangle takes the region with the largest sum over its three vertices. Each limb is then made one
// connected piece (MakeLimbsConnected).
#include <algorithm>
#include <cctype>
#include <map>
#include <set>
#include <sstream>

#include "segment_internal.h"

namespace spherechain::baker {
namespace segment_detail {
namespace {

bool Contains(const std::string& s, std::initializer_list<const char*> words) {
  for (const char* w : words)
    if (s.find(w) != std::string::npos) return true;
  return false;
}

}  // namespace

std::optional<Region> RegionOfBone(std::string_view bone_name) {
  int side = 0;  // +1 left, -1 right
  std::string joined;
  for (const std::string& t : NameTokens(bone_name)) {
    if (t == "l" || t == "left" || t == "lft") side = 1;
    else if (t == "r" || t == "right" || t == "rgt") side = -1;
    else if (t == "armature" || t == "skeleton") continue;
    else joined += t + " ";
  }
  if (Contains(joined, {"clavicle", "collar", "shoulder", "scapula", "breast", "pelvis", "spine", "chest", "neck",
                        "head", "hips ", "eye", "jaw", "tongue", "torso", "root"})) {
    return Region::kTorso;
  }
  const bool arm = Contains(joined, {"arm", "elbow", "wrist", "hand", "finger", "thumb", "index", "middle", "ring",
                                     "pinky", "metacarpal", "palm"});
  const bool leg = Contains(joined, {"leg", "thigh", "knee", "calf", "shin", "foot", "ankle", "toe", "heel"}) ||
                   (side != 0 && Contains(joined, {"hip"}));
  if (!arm && !leg) return Region::kTorso;
  if (side == 0) return std::nullopt;
  if (arm) return side > 0 ? Region::kLeftArm : Region::kRightArm;
  return side > 0 ? Region::kLeftLeg : Region::kRightLeg;
}

}  // namespace segment_detail

using namespace segment_detail;

Result<Segmentation> SegmentByRig(const Mesh& mesh, Context* ctx) {
  Context::Timer timer(ctx, "segment.rig");
  if (Status s = CheckMeshForSegmentation(mesh); !s) return s.error();
  if (!mesh.skin) return MakeError(Error::Code::kSegmentation, "segment (rig): the mesh has no skin");
  const Skin& skin = *mesh.skin;
  const uint32_t nv = mesh.vertex_count();
  if (skin.weight_offsets.size() != size_t(nv) + 1) {
    return MakeError(Error::Code::kSegmentation, "segment (rig): skin has " +
                                                     std::to_string(skin.weight_offsets.size()) +
                                                     " weight offsets for " + std::to_string(nv) + " vertices");
  }
  // Region of every joint.
  std::vector<uint8_t> joint_region(skin.joints.size(), static_cast<uint8_t>(Region::kTorso));
  std::set<std::string> unsided;
  std::array<std::set<std::string>, kRegionCount> bones_of;
  for (size_t j = 0; j < skin.joints.size(); ++j) {
    const int32_t node = skin.joints[j].node;
    const std::string name = (node >= 0 && size_t(node) < skin.nodes.size()) ? skin.nodes[size_t(node)].name : "";
    const std::optional<Region> r = RegionOfBone(name);
    if (!r) unsided.insert(name);
    joint_region[j] = static_cast<uint8_t>(r.value_or(Region::kTorso));
  }
  // Per-vertex region weights.
  std::vector<std::array<float, kRegionCount>> w(nv, std::array<float, kRegionCount>{});
  std::array<double, kRegionCount> total{};
  for (uint32_t v = 0; v < nv; ++v) {
    for (uint32_t k = skin.weight_offsets[v]; k < skin.weight_offsets[v + 1]; ++k) {
      const uint32_t j = skin.weight_joints[k];
      if (j >= joint_region.size()) continue;
      w[v][joint_region[j]] += skin.weights[k];
      total[joint_region[j]] += skin.weights[k];
      if (skin.weights[k] > 0) {
        const int32_t node = skin.joints[j].node;
        if (node >= 0 && size_t(node) < skin.nodes.size()) bones_of[joint_region[j]].insert(skin.nodes[size_t(node)].name);
      }
    }
  }
  std::string missing;
  for (int r = 0; r < kRegionCount - 1; ++r)
    if (total[r] <= 0) missing += std::string(missing.empty() ? "" : ", ") + RegionName(static_cast<Region>(r));
  if (!missing.empty()) {
    std::ostringstream names;
    size_t n = 0;
    for (const Node& node : skin.nodes) {
      if (n++ >= 40) {
        names << ", ...";
        break;
      }
      names << (n > 1 ? ", " : "") << node.name;
    }
    return MakeError(Error::Code::kSegmentation, "segment (rig): no weighted bone recognised for " + missing +
                                                     " (bones: " + names.str() + ")");
  }
  Segmentation seg;
  seg.method = "rig";
  const uint32_t nt = mesh.triangle_count();
  seg.triangle_regions.assign(nt, static_cast<uint8_t>(Region::kTorso));
  for (uint32_t t = 0; t < nt; ++t) {
    std::array<float, kRegionCount> sum{};
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < kRegionCount; ++r) sum[r] += w[mesh.indices[3 * t + k]][r];
    float best = 0;
    for (int r = 0; r < kRegionCount; ++r)
      if (sum[r] > best) best = sum[r], seg.triangle_regions[t] = static_cast<uint8_t>(r);
  }
  std::ostringstream notes;
  for (int r = 0; r < kRegionCount - 1; ++r) {
    notes << RegionSymbol(static_cast<Region>(r)) << " bones:";
    for (const std::string& b : bones_of[r]) notes << ' ' << b;
    notes << "; ";
  }
  if (!unsided.empty()) {
    notes << "limb bones without a side, counted as torso:";
    for (const std::string& b : unsided) notes << ' ' << b;
    notes << "; ";
  }
  seg.notes = notes.str();
  MakeLimbsConnected(mesh, seg.triangle_regions, seg.notes);
  ComputeVertexRegions(mesh, seg);
  seg.notes += RegionCounts(seg.triangle_regions);
  if (ctx) ctx->Info("segment (rig): " + seg.notes);
  return seg;
}

}  // namespace spherechain::baker
