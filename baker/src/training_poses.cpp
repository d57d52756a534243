#include "spherechain/baker/training_poses.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace spherechain::baker {

namespace {

// SplitMix64 (Steele, Lea, Flood 2014): a fixed, portable sequence (std:: distributions are not).
struct SplitMix64 {
  uint64_t state;
  uint64_t Next() {
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double Uniform() { return double(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

Eigen::Affine3d RestLocal(const Node& n) {
  const Eigen::Quaterniond q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.translate(Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]));
  t.rotate(q.normalized());
  t.scale(Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]));
  return t;
}

}  // namespace

std::vector<std::vector<float>> SampleTrainingPoses(const Mesh& mesh, const TrainingPoseOptions& options) {
  std::vector<std::vector<float>> poses;
  if (!mesh.skin || options.count == 0) return poses;
  const Skin& skin = *mesh.skin;
  const uint32_t V = mesh.vertex_count();
  const size_t N = skin.nodes.size();
  if (skin.weight_offsets.size() != size_t(V) + 1 || skin.joints.empty()) return poses;
  for (const SkinJoint& j : skin.joints)
    if (j.node < 0 || size_t(j.node) >= N) return poses;
  for (size_t n = 0; n < N; ++n)
    if (skin.nodes[n].parent >= int32_t(n)) return poses;  // parents first, as the importers store them

  std::vector<char> moves(N, 0);  // nodes a joint follows: the ones that bend
  for (const SkinJoint& j : skin.joints) moves[size_t(j.node)] = 1;
  std::vector<Eigen::Affine3d> rest(N);
  for (size_t n = 0; n < N; ++n) rest[n] = RestLocal(skin.nodes[n]);
  std::vector<Eigen::Matrix4d> inverse_bind(skin.joints.size());
  for (size_t j = 0; j < skin.joints.size(); ++j)
    inverse_bind[j] = Eigen::Map<const Eigen::Matrix4f>(skin.joints[j].inverse_bind.data()).cast<double>();

  SplitMix64 rng{options.seed};
  const double max_angle = std::clamp(double(options.max_angle_deg), 0.0, 90.0) * M_PI / 180.0;
  const uint32_t count = std::min<uint32_t>(options.count, 256);
  std::vector<Eigen::Affine3d> global(N);
  std::vector<Eigen::Matrix<double, 3, 4>> skinning(skin.joints.size());
  poses.resize(count);
  for (uint32_t p = 0; p < count; ++p) {
    for (size_t n = 0; n < N; ++n) {
      Eigen::Affine3d local = rest[n];
      if (moves[n]) {  // three draws a moving node, always, so the sequence does not depend on the tree
        const double z = 2.0 * rng.Uniform() - 1.0, phi = 2.0 * M_PI * rng.Uniform(), angle = max_angle * rng.Uniform();
        const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
        const Eigen::Vector3d axis(s * std::cos(phi), s * std::sin(phi), z);
        // In the node's own frame: after its translation and rest rotation, before its scale.
        const Node& node = skin.nodes[n];
        Eigen::Affine3d t = Eigen::Affine3d::Identity();
        t.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
        t.rotate(Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]).normalized());
        t.rotate(Eigen::AngleAxisd(angle, axis));
        t.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
        local = t;
      }
      const int32_t parent = skin.nodes[n].parent;
      global[n] = parent < 0 ? local : global[size_t(parent)] * local;
    }
    for (size_t j = 0; j < skin.joints.size(); ++j)
      skinning[j] = (global[size_t(skin.joints[j].node)].matrix() * inverse_bind[j]).topRows<3>();
    std::vector<float>& out = poses[p];
    out.assign(mesh.positions.begin(), mesh.positions.end());
    for (uint32_t v = 0; v < V; ++v) {
      const uint32_t b = skin.weight_offsets[v], e = skin.weight_offsets[v + 1];
      if (b == e) continue;
      const Eigen::Vector4d x(mesh.positions[3 * v], mesh.positions[3 * v + 1], mesh.positions[3 * v + 2], 1.0);
      Eigen::Vector3d y = Eigen::Vector3d::Zero();
      for (uint32_t k = b; k < e; ++k)
        if (skin.weight_joints[k] < skinning.size()) y += double(skin.weights[k]) * (skinning[skin.weight_joints[k]] * x);
      out[3 * v] = float(y.x()), out[3 * v + 1] = float(y.y()), out[3 * v + 2] = float(y.z());
    }
  }
  return poses;
}

}  // namespace spherechain::baker
