// spherechain playback — clip sampling, pose application, node globals, linear blend skinning.
#include "spherechain/playback/animation.h"

#include <algorithm>
#include <cmath>

namespace spherechain::playback {

namespace {

using Matrix4d = std::array<double, 16>;

Matrix4d ToDouble(const Matrix4& m) {
  Matrix4d d;
  for (int i = 0; i < 16; ++i) d[i] = m[i];
  return d;
}

Matrix4d Multiply(const Matrix4d& a, const Matrix4d& b) {
  Matrix4d r{};
  for (int c = 0; c < 4; ++c)
    for (int row = 0; row < 4; ++row) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + row] * b[c * 4 + k];
      r[c * 4 + row] = s;
    }
  return r;
}

Matrix4d TransformMatrixD(const Transform& t) {
  const double x = t.rotation[0], y = t.rotation[1], z = t.rotation[2], w = t.rotation[3];
  const double n = x * x + y * y + z * z + w * w;
  const double s = n > 0 ? 2.0 / n : 0.0;
  // Rotation matrix columns (glTF: R from unit quaternion), scaled per column by scale.
  const double r00 = 1 - s * (y * y + z * z), r01 = s * (x * y - z * w), r02 = s * (x * z + y * w);
  const double r10 = s * (x * y + z * w), r11 = 1 - s * (x * x + z * z), r12 = s * (y * z - x * w);
  const double r20 = s * (x * z - y * w), r21 = s * (y * z + x * w), r22 = 1 - s * (x * x + y * y);
  const double sx = t.scale[0], sy = t.scale[1], sz = t.scale[2];
  return {r00 * sx, r10 * sx, r20 * sx, 0,  //
          r01 * sy, r11 * sy, r21 * sy, 0,  //
          r02 * sz, r12 * sz, r22 * sz, 0,  //
          t.translation[0], t.translation[1], t.translation[2], 1};
}

bool Finite(float v) { return std::isfinite(v); }

const char* PathName(Channel::Path p) {
  switch (p) {
    case Channel::Path::kTranslation: return "translation";
    case Channel::Path::kRotation: return "rotation";
    case Channel::Path::kScale: return "scale";
  }
  return "?";
}

size_t Width(Channel::Path p) { return p == Channel::Path::kRotation ? 4 : 3; }

}  // namespace

// ---- quaternions ----------------------------------------------------------------------------------

Quat QuatFromAxisAngle(const std::array<float, 3>& axis, float degrees) {
  const double l = std::sqrt(double(axis[0]) * axis[0] + double(axis[1]) * axis[1] + double(axis[2]) * axis[2]);
  if (!(l > 0) || !std::isfinite(l)) return {0, 0, 0, 1};
  const double half = 0.5 * double(degrees) * 3.14159265358979323846 / 180.0;
  const double s = std::sin(half) / l;
  return {float(axis[0] * s), float(axis[1] * s), float(axis[2] * s), float(std::cos(half))};
}

Quat QuatMultiply(const Quat& a, const Quat& b) {
  return {a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
          a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
          a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
          a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]};
}

Quat QuatConjugate(const Quat& q) { return {-q[0], -q[1], -q[2], q[3]}; }

Quat QuatNormalize(const Quat& q) {
  const double n = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
  if (!(n > 0) || !std::isfinite(n)) return {0, 0, 0, 1};
  return {float(q[0] / n), float(q[1] / n), float(q[2] / n), float(q[3] / n)};
}

Quat QuatSlerpArc(const Quat& a, const Quat& b, float u) {
  double d = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2] + double(a[3]) * b[3];
  d = std::clamp(d, -1.0, 1.0);
  const double theta = std::acos(d);
  const double st = std::sin(theta);
  double wa, wb;
  if (st < 1e-6) {  // a ≈ ±b: the arc is (nearly) a point or undefined; lerp and normalise
    wa = 1.0 - u;
    wb = u;
  } else {
    wa = std::sin((1.0 - u) * theta) / st;
    wb = std::sin(u * theta) / st;
  }
  return QuatNormalize({float(wa * a[0] + wb * b[0]), float(wa * a[1] + wb * b[1]), float(wa * a[2] + wb * b[2]),
                        float(wa * a[3] + wb * b[3])});
}

Quat QuatSlerp(const Quat& a, const Quat& b, float u) {
  const double d = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2] + double(a[3]) * b[3];
  if (d < 0) return QuatSlerpArc(a, {-b[0], -b[1], -b[2], -b[3]}, u);
  return QuatSlerpArc(a, b, u);
}

std::array<float, 3> QuatRotate(const Quat& q, const std::array<float, 3>& v) {
  const Quat p = QuatMultiply(QuatMultiply(q, {v[0], v[1], v[2], 0}), QuatConjugate(q));
  return {p[0], p[1], p[2]};
}

// ---- locals ---------------------------------------------------------------------------------------

int32_t FindNode(const Skin& skin, const std::string& name) {
  for (size_t i = 0; i < skin.nodes.size(); ++i)
    if (skin.nodes[i].name == name) return static_cast<int32_t>(i);
  return -1;
}

void RestLocals(const Skin& skin, std::vector<Transform>* locals) {
  locals->resize(skin.nodes.size());
  for (size_t i = 0; i < skin.nodes.size(); ++i) {
    const Node& n = skin.nodes[i];
    (*locals)[i] = Transform{n.translation, n.rotation, n.scale};
  }
}

Status PoseLocals(const Skin& skin, const Pose& pose, std::vector<Transform>* locals) {
  RestLocals(skin, locals);
  for (const Pose::Rotation& r : pose.rotations) {
    if (r.node < 0 || static_cast<size_t>(r.node) >= skin.nodes.size())
      return MakeError(Error::Code::kConfig, "pose '" + pose.name + "': node index " + std::to_string(r.node) +
                                                 " out of range (the skin has " + std::to_string(skin.nodes.size()) +
                                                 " nodes)");
    (*locals)[static_cast<size_t>(r.node)].rotation = QuatNormalize(r.rotation);
  }
  return Ok{};
}

Status ValidateClip(const Skin& skin, const Clip& clip) {
  for (size_t c = 0; c < clip.channels.size(); ++c) {
    const Channel& ch = clip.channels[c];
    // The message's place, built only for an error (SampleClip validates every frame).
    const auto where = [&] { return "clip '" + clip.name + "' channel " + std::to_string(c) + " (" + PathName(ch.path) + ")"; };
    if (ch.node < 0 || static_cast<size_t>(ch.node) >= skin.nodes.size())
      return MakeError(Error::Code::kFormat, where() + ": node " + std::to_string(ch.node) + " out of range (" +
                                                 std::to_string(skin.nodes.size()) + " nodes)");
    if (ch.times.empty()) return MakeError(Error::Code::kFormat, where() + ": no keys");
    if (ch.values.size() != ch.times.size() * Width(ch.path))
      return MakeError(Error::Code::kFormat, where() + ": " + std::to_string(ch.values.size()) + " values for " +
                                                 std::to_string(ch.times.size()) + " keys of " +
                                                 std::to_string(Width(ch.path)) + " floats");
    for (size_t k = 0; k < ch.times.size(); ++k)
      if (!Finite(ch.times[k]) || (k > 0 && ch.times[k] < ch.times[k - 1]))
        return MakeError(Error::Code::kFormat, where() + ": key time " + std::to_string(k) + " not finite or decreasing");
    for (float v : ch.values)
      if (!Finite(v)) return MakeError(Error::Code::kFormat, where() + ": non-finite key value");
  }
  return Ok{};
}

Status SampleClip(const Skin& skin, const Clip& clip, float time_s, std::vector<Transform>* locals) {
  if (auto s = ValidateClip(skin, clip); !s.ok()) return s;
  RestLocals(skin, locals);
  for (const Channel& ch : clip.channels) {
    const size_t w = Width(ch.path);
    const size_t n = ch.times.size();
    // Keys k0, k1 and the blend u between them.
    size_t k0 = 0, k1 = 0;
    float u = 0.0f;
    if (time_s <= ch.times.front()) {
      k0 = k1 = 0;
    } else if (time_s >= ch.times.back()) {
      k0 = k1 = n - 1;
    } else {
      const size_t hi = static_cast<size_t>(std::upper_bound(ch.times.begin(), ch.times.end(), time_s) - ch.times.begin());
      k0 = hi - 1;
      k1 = hi;
      const float span = ch.times[k1] - ch.times[k0];
      u = span > 0 ? (time_s - ch.times[k0]) / span : 0.0f;
      if (ch.interpolation == Channel::Interpolation::kStep) {
        k1 = k0;
        u = 0.0f;
      }
    }
    const float* a = &ch.values[k0 * w];
    const float* b = &ch.values[k1 * w];
    Transform& t = (*locals)[static_cast<size_t>(ch.node)];
    switch (ch.path) {
      case Channel::Path::kTranslation:
        for (int i = 0; i < 3; ++i) t.translation[i] = a[i] + u * (b[i] - a[i]);
        break;
      case Channel::Path::kScale:
        for (int i = 0; i < 3; ++i) t.scale[i] = a[i] + u * (b[i] - a[i]);
        break;
      case Channel::Path::kRotation:
        t.rotation = QuatSlerp(QuatNormalize({a[0], a[1], a[2], a[3]}), QuatNormalize({b[0], b[1], b[2], b[3]}), u);
        break;
    }
  }
  return Ok{};
}

// ---- matrices ---------------------------------------------------------------------------------------

Matrix4 TransformMatrix(const Transform& t) {
  const Matrix4d d = TransformMatrixD(t);
  Matrix4 m;
  for (int i = 0; i < 16; ++i) m[i] = float(d[i]);
  return m;
}

Matrix4 MatrixMultiply(const Matrix4& a, const Matrix4& b) {
  const Matrix4d d = Multiply(ToDouble(a), ToDouble(b));
  Matrix4 m;
  for (int i = 0; i < 16; ++i) m[i] = float(d[i]);
  return m;
}

Status GlobalMatrices(const Skin& skin, const std::vector<Transform>& locals, std::vector<Matrix4>* globals) {
  const size_t n = skin.nodes.size();
  if (locals.size() != n)
    return MakeError(Error::Code::kConfig, std::to_string(locals.size()) + " local transforms for " +
                                               std::to_string(n) + " nodes");
  globals->resize(n);
  for (size_t i = 0; i < n; ++i) {
    const int32_t p = skin.nodes[i].parent;
    if (p >= static_cast<int32_t>(i))
      return MakeError(Error::Code::kConfig, "node " + std::to_string(i) + " ('" + skin.nodes[i].name +
                                                 "') has parent " + std::to_string(p) + ", not parents-first");
    const Matrix4d local = TransformMatrixD(locals[i]);
    const Matrix4d g = p < 0 ? local : Multiply(ToDouble((*globals)[static_cast<size_t>(p)]), local);
    for (int k = 0; k < 16; ++k) (*globals)[i][k] = float(g[k]);
  }
  return Ok{};
}

Status SkinningMatrices(const Skin& skin, const std::vector<Matrix4>& globals, std::vector<Matrix4>* matrices) {
  if (globals.size() != skin.nodes.size())
    return MakeError(Error::Code::kConfig, std::to_string(globals.size()) + " global matrices for " +
                                               std::to_string(skin.nodes.size()) + " nodes");
  matrices->resize(skin.joints.size());
  for (size_t j = 0; j < skin.joints.size(); ++j) {
    const int32_t node = skin.joints[j].node;
    if (node < 0 || static_cast<size_t>(node) >= globals.size())
      return MakeError(Error::Code::kConfig, "joint " + std::to_string(j) + " names node " + std::to_string(node) +
                                                 " out of range");
    (*matrices)[j] = MatrixMultiply(globals[static_cast<size_t>(node)], skin.joints[j].inverse_bind);
  }
  return Ok{};
}

Status SkinPositions(const Mesh& mesh, const std::vector<Matrix4>& matrices, float* out, size_t out_floats) {
  if (!mesh.skin) return MakeError(Error::Code::kConfig, "the mesh has no skin ('" + mesh.source_path + "')");
  const Skin& skin = *mesh.skin;
  const size_t nv = mesh.vertex_count();
  if (!out || out_floats != nv * 3)
    return MakeError(Error::Code::kConfig, "output buffer holds " + std::to_string(out_floats) + " floats, needs 3 x " +
                                               std::to_string(nv) + " vertices");
  if (matrices.size() != skin.joints.size())
    return MakeError(Error::Code::kConfig, std::to_string(matrices.size()) + " skinning matrices for " +
                                               std::to_string(skin.joints.size()) + " joints");
  if (skin.weight_offsets.size() != nv + 1 || skin.weight_offsets.back() > skin.weight_joints.size() ||
      skin.weight_joints.size() != skin.weights.size())
    return MakeError(Error::Code::kConfig, "skin weight rows do not match the mesh's " + std::to_string(nv) +
                                               " vertices");
  const float* p = mesh.positions.data();
  for (size_t v = 0; v < nv; ++v) {
    const double x = p[v * 3], y = p[v * 3 + 1], z = p[v * 3 + 2];
    const uint32_t b = skin.weight_offsets[v], e = skin.weight_offsets[v + 1];
    if (b >= e) {
      out[v * 3] = p[v * 3];
      out[v * 3 + 1] = p[v * 3 + 1];
      out[v * 3 + 2] = p[v * 3 + 2];
      continue;
    }
    double ox = 0, oy = 0, oz = 0;
    for (uint32_t k = b; k < e; ++k) {
      const uint32_t j = skin.weight_joints[k];
      if (j >= matrices.size())
        return MakeError(Error::Code::kConfig, "vertex " + std::to_string(v) + " weighted to joint " +
                                                   std::to_string(j) + " out of range");
      const Matrix4& m = matrices[j];
      const double w = skin.weights[k];
      ox += w * (m[0] * x + m[4] * y + m[8] * z + m[12]);
      oy += w * (m[1] * x + m[5] * y + m[9] * z + m[13]);
      oz += w * (m[2] * x + m[6] * y + m[10] * z + m[14]);
    }
    out[v * 3] = float(ox);
    out[v * 3 + 1] = float(oy);
    out[v * 3 + 2] = float(oz);
  }
  return Ok{};
}

Status SkinLocals(const Mesh& mesh, const std::vector<Transform>& locals, SkinningScratch* scratch, float* out,
                  size_t out_floats) {
  if (!mesh.skin) return MakeError(Error::Code::kConfig, "the mesh has no skin ('" + mesh.source_path + "')");
  if (auto s = GlobalMatrices(*mesh.skin, locals, &scratch->globals); !s.ok()) return s;
  if (auto s = SkinningMatrices(*mesh.skin, scratch->globals, &scratch->matrices); !s.ok()) return s;
  return SkinPositions(mesh, scratch->matrices, out, out_floats);
}

Status SkinClip(const Mesh& mesh, const Clip& clip, float time_s, SkinningScratch* scratch, float* out,
                size_t out_floats) {
  if (!mesh.skin) return MakeError(Error::Code::kConfig, "the mesh has no skin ('" + mesh.source_path + "')");
  if (auto s = SampleClip(*mesh.skin, clip, time_s, &scratch->locals); !s.ok()) return s;
  return SkinLocals(mesh, scratch->locals, scratch, out, out_floats);
}

Status SkinPose(const Mesh& mesh, const Pose& pose, SkinningScratch* scratch, float* out, size_t out_floats) {
  if (!mesh.skin) return MakeError(Error::Code::kConfig, "the mesh has no skin ('" + mesh.source_path + "')");
  if (auto s = PoseLocals(*mesh.skin, pose, &scratch->locals); !s.ok()) return s;
  return SkinLocals(mesh, scratch->locals, scratch, out, out_floats);
}

}  // namespace spherechain::playback
