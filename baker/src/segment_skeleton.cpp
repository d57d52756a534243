// spherechain baker — the any-skeleton path (issue 11): segmentation of a rigged creature that is not a
// standing biped (quadrupeds, many-legged creatures, tails, necks, wings) from its bone tree.
//
// 1. Each bone's share of the body: the skin weights of every vertex times the vertex's area (a third
//    of its triangles'), summed per bone — so a bone's share is the surface it moves, whatever the
//    vertex density.
// 2. A junction is a bone where three or more branches meet that each move at least
//    SkeletonOptions::limb_min_share of the surface (its child subtrees, and the rest of the tree above
//    it): the pelvis (tail, two hind legs, the spine ahead), the chest (two fore legs, the neck, the spine
//    behind), a spider's body (eight legs).
// 3. The trunk is the smallest subtree of bones joining every junction (the spine between the hips and
//    the shoulders; one bone when there is one junction). Every branch off the trunk that moves at least
//    limb_min_share is a limb, with everything below it (a head with its ears and jaw, a paw with its
//    toes); smaller branches (a lone ear on the spine, a twist bone) stay with the trunk.
// 4. A vertex sums its weights per region, a triangle takes the region with the largest sum over its
//    three corners (as SegmentByRig), each limb is made one connected piece (MakeLimbsConnected), and
//    limbs left without a triangle are dropped.
// 5. Names: a limb after the common stem of the bones along its main chain ("HindLeg_L_01".."_04" →
//    "HindLeg_L", "Tail01".."Tail06" → "Tail"), else after its bone moving the most surface ("Neck");
//    the trunk is "trunk". Two limbs whose names differ only by a side token (l/left, r/right) are a
//    mirror pair. The trunk's axis is the principal axis of its vertices (area-weighted).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <map>
#include <numeric>
#include <sstream>

#include "segment_internal.h"

namespace spherechain::baker {

using namespace segment_detail;

namespace {

Error NoLimbs(const std::string& why) {
  return MakeError(Error::Code::kSegmentation, "segment (skeleton): no recognisable limbs: " + why);
}

std::string Percent(double x) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1) << 100.0 * x << " %";
  return o.str();
}

// "HindLeg_L_01", "HindLeg_L_02", ... → "HindLeg_L": the common prefix, cut back to the last character
// that is neither a digit nor a separator.
std::string CommonStem(const std::vector<std::string>& names) {
  if (names.empty()) return {};
  std::string stem = names.front();
  for (const std::string& n : names) {
    size_t k = 0;
    while (k < stem.size() && k < n.size() && stem[k] == n[k]) ++k;
    stem.resize(k);
  }
  while (!stem.empty() && !std::isalpha(static_cast<unsigned char>(stem.back()))) stem.pop_back();
  return stem;
}

}  // namespace

Result<Segmentation> SegmentBySkeleton(const Mesh& mesh, const SkeletonOptions& options, Context* ctx) {
  Context::Timer timer(ctx, "segment.skeleton");
  if (Status s = CheckMeshForSegmentation(mesh); !s) return s.error();
  if (!mesh.skin)
    return MakeError(Error::Code::kSegmentation,
                     "segment (skeleton): the mesh has no skin: the any-skeleton path needs a rig (bones and skin "
                     "weights) to find the limbs of a creature");
  if (!(options.limb_min_share > 0.0 && options.limb_min_share < 0.5))
    return MakeError(Error::Code::kSegmentation, "segment (skeleton): limb_min_share must be in (0, 0.5)");
  const Skin& skin = *mesh.skin;
  const uint32_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
  if (skin.weight_offsets.size() != size_t(nv) + 1)
    return MakeError(Error::Code::kSegmentation, "segment (skeleton): skin has " +
                                                     std::to_string(skin.weight_offsets.size()) +
                                                     " weight offsets for " + std::to_string(nv) + " vertices");
  const size_t nn = skin.nodes.size();
  for (size_t n = 0; n < nn; ++n)
    if (skin.nodes[n].parent >= int32_t(n))
      return MakeError(Error::Code::kSegmentation, "segment (skeleton): the bone tree is not stored parents first");

  // 1. Surface moved by each bone (node): Σ_v area(v) · w(v, bone).
  std::vector<double> vertex_area(nv, 0.0);
  {
    const std::vector<double> tri_area = TriangleAreas(mesh);
    for (uint32_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) vertex_area[mesh.indices[3 * t + k]] += tri_area[t] / 3.0;
  }
  std::vector<int32_t> joint_node(skin.joints.size(), -1);
  for (size_t j = 0; j < skin.joints.size(); ++j)
    if (skin.joints[j].node >= 0 && size_t(skin.joints[j].node) < nn) joint_node[j] = skin.joints[j].node;
  std::vector<double> own(nn, 0.0);
  for (uint32_t v = 0; v < nv; ++v)
    for (uint32_t k = skin.weight_offsets[v]; k < skin.weight_offsets[v + 1]; ++k) {
      const uint32_t j = skin.weight_joints[k];
      if (j < joint_node.size() && joint_node[j] >= 0 && skin.weights[k] > 0.0f)
        own[size_t(joint_node[j])] += vertex_area[v] * double(skin.weights[k]);
    }
  const double total = std::accumulate(own.begin(), own.end(), 0.0);
  std::vector<size_t> weighted;
  for (size_t n = 0; n < nn; ++n)
    if (own[n] > 0.0) weighted.push_back(n);
  auto bone_list = [&](const std::vector<size_t>& ids, size_t max) {
    std::string s;
    for (size_t i = 0; i < ids.size() && i < max; ++i) s += (i ? ", " : "") + skin.nodes[ids[i]].name;
    if (ids.size() > max) s += ", ...";
    return s;
  };
  if (!(total > 0.0)) return NoLimbs("no bone carries skin weight");
  if (weighted.size() < 3)
    return NoLimbs("the skin uses " + std::to_string(weighted.size()) + " bone" + (weighted.size() == 1 ? "" : "s") +
                   " (" + bone_list(weighted, 8) + "): a creature needs limbs branching off a trunk");

  // 2. Subtree shares and junctions.
  std::vector<double> sub = own;
  for (size_t n = nn; n-- > 0;)
    if (skin.nodes[n].parent >= 0) sub[size_t(skin.nodes[n].parent)] += sub[n];
  std::vector<std::vector<size_t>> children(nn);
  for (size_t n = 0; n < nn; ++n)
    if (skin.nodes[n].parent >= 0) children[size_t(skin.nodes[n].parent)].push_back(n);
  const double min_share = options.limb_min_share * total;
  std::vector<uint8_t> junction(nn, 0);
  size_t junctions = 0;
  for (size_t n = 0; n < nn; ++n) {
    int branches = total - sub[n] >= min_share ? 1 : 0;
    for (size_t c : children[n]) branches += sub[c] >= min_share;
    if (branches >= 3) junction[n] = 1, ++junctions;
  }
  if (junctions == 0)
    return NoLimbs("no bone has three branches that each move " + Percent(options.limb_min_share) +
                   " of the surface (" + std::to_string(weighted.size()) + " weighted bones: " +
                   bone_list(weighted, 12) + ")");

  // 3. The trunk: the smallest subtree joining every junction.
  std::vector<size_t> below(nn, 0);  // junctions in each subtree
  for (size_t n = nn; n-- > 0;) {
    below[n] += junction[n];
    if (skin.nodes[n].parent >= 0) below[size_t(skin.nodes[n].parent)] += below[n];
  }
  size_t top = 0;  // the deepest bone above every junction
  for (size_t n = 0; n < nn; ++n)
    if (below[n] == junctions) top = n;  // parents first: the last one found is the deepest
  std::vector<uint8_t> in_top(nn, 0), trunk(nn, 0);
  for (size_t n = 0; n < nn; ++n) {
    in_top[n] = n == top || (skin.nodes[n].parent >= 0 && in_top[size_t(skin.nodes[n].parent)]);
    trunk[n] = in_top[n] && below[n] > 0;
  }

  // Limbs: the branches off the trunk that move at least limb_min_share; the rest of the tree above
  // the trunk is one more branch.
  struct Limb {
    size_t root = 0;              // first bone of the branch (top's ancestor side: top's parent)
    std::vector<size_t> bones;    // every bone of the branch, tree order
    double share = 0.0;
  };
  std::vector<Limb> limbs;
  std::vector<int> region_of_node(nn, -1);  // -1: trunk
  auto collect = [&](size_t root, Limb* limb) {
    std::vector<size_t> stack{root};
    while (!stack.empty()) {
      const size_t n = stack.back();
      stack.pop_back();
      limb->bones.push_back(n);
      for (auto it = children[n].rbegin(); it != children[n].rend(); ++it) stack.push_back(*it);
    }
    std::sort(limb->bones.begin(), limb->bones.end());
  };
  for (size_t n = 0; n < nn; ++n) {
    if (!trunk[n]) continue;
    for (size_t c : children[n]) {
      if (trunk[c] || sub[c] < min_share) continue;
      Limb limb;
      limb.root = c;
      limb.share = sub[c] / total;
      collect(c, &limb);
      limbs.push_back(std::move(limb));
    }
  }
  if (total - sub[top] >= min_share) {
    Limb limb;  // the tree above the trunk (a skeleton rooted at its head, say)
    limb.share = (total - sub[top]) / total;
    for (size_t n = 0; n < nn; ++n)
      if (!in_top[n]) limb.bones.push_back(n);
    // Its first bone: top's parent; when top is a root, the skin is a forest (a skin whose joints leave
    // out a bone between two of them, say) and the branch is the other trees: the root moving the most.
    // (There is one: the weight outside top's tree lies on a tree of its own.)
    if (skin.nodes[top].parent >= 0) {
      limb.root = size_t(skin.nodes[top].parent);
    } else {
      limb.root = SIZE_MAX;
      for (size_t n : limb.bones)
        if (skin.nodes[n].parent < 0 && (limb.root == SIZE_MAX || sub[n] > sub[limb.root])) limb.root = n;
    }
    limbs.push_back(std::move(limb));
  }
  if (limbs.size() + 1 > size_t(kMaxRegions))
    return NoLimbs(std::to_string(limbs.size()) + " branches off the trunk, more than the " +
                   std::to_string(kMaxRegions - 1) + " limbs an asset can hold");
  for (size_t l = 0; l < limbs.size(); ++l)
    for (size_t n : limbs[l].bones) region_of_node[n] = int(l);

  // 4. Regions per vertex and triangle.
  const int nreg = int(limbs.size()) + 1;
  const int trunk_region = nreg - 1;
  std::vector<int> joint_region(skin.joints.size(), trunk_region);
  for (size_t j = 0; j < skin.joints.size(); ++j)
    if (joint_node[j] >= 0 && region_of_node[size_t(joint_node[j])] >= 0)
      joint_region[j] = region_of_node[size_t(joint_node[j])];
  std::vector<float> w(size_t(nv) * size_t(nreg), 0.0f);
  for (uint32_t v = 0; v < nv; ++v)
    for (uint32_t k = skin.weight_offsets[v]; k < skin.weight_offsets[v + 1]; ++k) {
      const uint32_t j = skin.weight_joints[k];
      if (j < joint_region.size()) w[size_t(v) * nreg + size_t(joint_region[j])] += skin.weights[k];
    }
  Segmentation seg;
  seg.method = "skeleton";
  seg.triangle_regions.assign(nt, uint8_t(trunk_region));
  std::vector<float> sum(static_cast<size_t>(nreg), 0.0f);
  for (uint32_t t = 0; t < nt; ++t) {
    std::fill(sum.begin(), sum.end(), 0.0f);
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < nreg; ++r) sum[size_t(r)] += w[size_t(mesh.indices[3 * t + k]) * nreg + size_t(r)];
    float best = 0.0f;
    for (int r = 0; r < nreg; ++r)
      if (sum[size_t(r)] > best) best = sum[size_t(r)], seg.triangle_regions[t] = uint8_t(r);
  }
  // Names and the layout (before the cleanup, which reads which region is the trunk).
  std::vector<double> shares;  // per region, the share of the surface its bones move
  seg.layout.regions.clear();
  seg.layout.paper = false;
  for (const Limb& limb : limbs) {
    // Main chain: from the branch's first bone, always into the child moving the most surface.
    std::vector<std::string> chain_names;
    size_t heaviest = limb.root;
    for (size_t n : limb.bones)
      if (own[n] > own[heaviest]) heaviest = n;
    for (size_t n = limb.root;;) {
      if (own[n] > 0.0 || !children[n].empty()) chain_names.push_back(skin.nodes[n].name);
      size_t next = SIZE_MAX;
      for (size_t c : children[n])
        if (region_of_node[c] == region_of_node[limb.root] && (next == SIZE_MAX || sub[c] > sub[next])) next = c;
      if (next == SIZE_MAX) break;
      n = next;
    }
    std::string name = chain_names.size() >= 2 ? CommonStem(chain_names) : std::string();
    if (name.size() < 2) name = skin.nodes[heaviest].name;
    if (name.empty()) name = "limb" + std::to_string(seg.layout.regions.size());
    RegionInfo info;
    info.name = name;
    info.kind = RegionKind::kLimb;
    info.bone = skin.nodes[limb.root].name;
    seg.layout.regions.push_back(std::move(info));
    shares.push_back(limb.share);
  }
  {
    RegionInfo t;
    t.name = "trunk";
    t.kind = RegionKind::kTrunk;
    t.bone = skin.nodes[top].name;
    seg.layout.regions.push_back(std::move(t));
    shares.push_back(0.0);
  }
  std::string notes = "trunk bones:";
  for (size_t n = 0; n < nn; ++n)
    if (trunk[n]) notes += " " + skin.nodes[n].name;
  notes += "; ";
  MakeLimbsConnected(mesh, seg.triangle_regions, notes, seg.layout, /*keep_loose_parts=*/true);

  // Limbs left without a triangle are dropped (their region values closed up).
  std::vector<size_t> count(size_t(nreg), 0);
  for (uint8_t r : seg.triangle_regions) ++count[r];
  if (count[size_t(trunk_region)] == 0)
    return NoLimbs("the trunk's bones (" + bone_list([&] {
                     std::vector<size_t> ids;
                     for (size_t n = 0; n < nn; ++n)
                       if (trunk[n]) ids.push_back(n);
                     return ids;
                   }(), 8) + ") dominate no triangle");
  {
    std::vector<int> remap(size_t(nreg), -1);
    RegionLayout kept;
    kept.paper = false;
    kept.regions.clear();
    std::vector<double> kept_shares;
    std::string dropped;
    for (int r = 0; r < nreg; ++r) {
      if (count[size_t(r)] == 0) {
        dropped += (dropped.empty() ? "" : ", ") + seg.layout.regions[size_t(r)].name;
        continue;
      }
      remap[size_t(r)] = int(kept.regions.size());
      kept.regions.push_back(seg.layout.regions[size_t(r)]);
      kept_shares.push_back(shares[size_t(r)]);
    }
    if (!dropped.empty()) {
      for (uint8_t& r : seg.triangle_regions) r = uint8_t(remap[r]);
      const int trunk_kept = remap[size_t(trunk_region)];
      for (int& r : joint_region) r = remap[size_t(r)] >= 0 ? remap[size_t(r)] : trunk_kept;  // a dropped limb's bones: the trunk's
      seg.layout = std::move(kept);
      shares = std::move(kept_shares);
      notes += "limbs without a triangle dropped: " + dropped + "; ";
    }
  }
  if (seg.layout.count() < 3)
    return NoLimbs("only " + std::to_string(seg.layout.count() - 1) +
                   " limb keeps triangles of its own (a creature needs two limbs besides the trunk)");
  seg.joint_regions.assign(joint_region.begin(), joint_region.end());
  // Unique names, mirror pairs, the trunk's axis.
  {
    // A stem two limbs share ("Bone" of Bone.002.., Bone.003..) names neither: they take their first
    // bone's name; what still repeats gets _2, _3.
    std::map<std::string, int> uses, seen;
    for (const RegionInfo& info : seg.layout.regions) ++uses[info.name];
    for (RegionInfo& info : seg.layout.regions)
      if (uses[info.name] > 1 && info.kind == RegionKind::kLimb && !info.bone.empty()) info.name = info.bone;
    for (RegionInfo& info : seg.layout.regions)
      if (int k = seen[info.name]++; k > 0) info.name += "_" + std::to_string(k + 1);
  }
  PairMirrorLimbs(seg.layout);
  seg.layout.trunk_axis = TrunkAxis(mesh, seg.triangle_regions, seg.layout.trunk());
  ComputeVertexRegions(mesh, seg);
  std::ostringstream o;
  o << notes << "limbs (first bone, share of the surface its bones move):";
  for (int r = 0; r + 1 < seg.layout.count(); ++r) {
    const RegionInfo& info = seg.layout.regions[size_t(r)];
    o << (r ? ", " : " ") << info.name << " (" << info.bone << ", " << Percent(shares[size_t(r)]) << ")";
  }
  o << "; " << RegionCounts(seg.triangle_regions, seg.layout);
  seg.notes = o.str();
  if (ctx) ctx->Info("segment (skeleton): " + seg.notes);
  return seg;
}

}  // namespace spherechain::baker
