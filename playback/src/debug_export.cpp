#include "spherechain/playback/debug_export.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <numeric>
#include <sstream>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <tiny_gltf.h>

#include "spherechain/import/file_io.h"
#include "utf8.h"

namespace spherechain::playback {

namespace {

// Element i's region in an optional Asset.sphere_regions / triangle_regions (LoadAsset: #S / #T entries when
// present); past every region (drawn grey, as the trunk) when the asset has none or i is past its entries (a
// mesh with more triangles than the asset: the pictures draw it, never read past the table).
uint32_t RegionAt(const flatbuffers::Vector<uint8_t>* regions, uint32_t i) {
  return regions && i < regions->size() ? regions->Get(i) : 0xffu;
}


Eigen::Vector3f UpOf(UpAxis a) {
  return a == UpAxis::kZ ? Eigen::Vector3f::UnitZ() : a == UpAxis::kX ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY();
}

// Character frame from the asset: up, its left (left arm spheres minus right arm spheres), front.
struct Frame {
  Eigen::Vector3f up, left, front;
};

Frame CharacterFrame(const Mesh& mesh, const runtime::AssetView& a) {
  Frame f;
  f.up = UpOf(mesh.up_axis);
  Eigen::Vector3f l = Eigen::Vector3f::Zero(), r = Eigen::Vector3f::Zero();
  int nl = 0, nr = 0;
  const auto* spheres = a.asset->spheres();
  const auto* regions = a.asset->sphere_regions();
  for (uint32_t s = 0; s < a.sphere_count; ++s) {
    const auto& c = spheres->Get(s)->center();
    const Eigen::Vector3f p(c.x(), c.y(), c.z());
    const uint32_t region = RegionAt(regions, s);
    if (region == 0 || region == 2) { l += p; ++nl; }
    if (region == 1 || region == 3) { r += p; ++nr; }
  }
  Eigen::Vector3f left = (nl && nr) ? Eigen::Vector3f(l / float(nl) - r / float(nr)) : Eigen::Vector3f::UnitX();
  if (a.asset->regions() && !a.asset->biped()) {
    // A creature: "front" is along its trunk (the principal axis of the trunk spheres' centres), so the
    // first view looks at its side.
    const uint32_t trunk = runtime::RegionCount(a) - 1;
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    int n = 0;
    for (uint32_t s = 0; s < a.sphere_count; ++s)
      if (RegionAt(regions, s) == trunk) {
        const auto& c = spheres->Get(s)->center();
        mean += Eigen::Vector3f(c.x(), c.y(), c.z());
        ++n;
      }
    Eigen::Matrix3f cov = Eigen::Matrix3f::Zero();
    for (uint32_t s = 0; s < a.sphere_count && n > 0; ++s)
      if (RegionAt(regions, s) == trunk) {
        const auto& c = spheres->Get(s)->center();
        const Eigen::Vector3f d = Eigen::Vector3f(c.x(), c.y(), c.z()) - mean / float(n);
        cov += d * d.transpose();
      }
    const Eigen::Matrix3f flat = Eigen::Matrix3f::Identity() - f.up * f.up.transpose();  // the horizontal part
    cov = flat * cov * flat;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> es(cov);
    const Eigen::Vector3f along = es.eigenvectors().col(2);
    left = f.up.cross(along);  // front = left × up = along
  }
  left -= left.dot(f.up) * f.up;
  if (left.norm() < 1e-9f) left = f.up.unitOrthogonal();
  f.left = left.normalized();
  f.front = f.left.cross(f.up).normalized();
  return f;
}

std::string Hex(const std::array<float, 3>& c, float shade = 1.0f) {
  char buf[8];
  auto q = [&](float x) { return int(std::clamp(x * shade, 0.0f, 1.0f) * 255.0f + 0.5f); };
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", q(c[0]), q(c[1]), q(c[2]));
  return buf;
}

}  // namespace

std::array<float, 3> RegionColor(Region r) {
  switch (r) {
    case Region::kLeftArm: return {0.90f, 0.45f, 0.10f};
    case Region::kRightArm: return {0.20f, 0.45f, 0.85f};
    case Region::kLeftLeg: return {0.20f, 0.65f, 0.30f};
    case Region::kRightLeg: return {0.55f, 0.40f, 0.75f};
    case Region::kTorso: break;
  }
  return {0.72f, 0.72f, 0.72f};
}

namespace {
struct Named { const char* name; std::array<float, 3> rgb; };
// No red, amber or magenta: the pictures mark contacts with them (RenderFrameSvg, the viewer).
constexpr Named kPalette[12] = {
    {"orange", {0.90f, 0.45f, 0.10f}}, {"blue", {0.20f, 0.45f, 0.85f}},  {"green", {0.20f, 0.65f, 0.30f}},
    {"purple", {0.55f, 0.40f, 0.75f}}, {"teal", {0.10f, 0.60f, 0.60f}},  {"brown", {0.55f, 0.35f, 0.15f}},
    {"pink", {0.95f, 0.60f, 0.80f}},   {"olive", {0.50f, 0.55f, 0.10f}}, {"navy", {0.15f, 0.20f, 0.50f}},
    {"cyan", {0.40f, 0.85f, 0.95f}},   {"lime", {0.60f, 0.85f, 0.30f}},  {"slate", {0.45f, 0.50f, 0.60f}}};
}  // namespace

std::array<float, 3> RegionColor(const runtime::AssetView& a, uint32_t region) {
  if (!a.valid() || !a.asset->regions()) return RegionColor(static_cast<Region>(std::min<uint32_t>(region, 4)));
  if (runtime::IsTrunkRegion(a, region) || region >= runtime::RegionCount(a)) return {0.72f, 0.72f, 0.72f};
  return kPalette[region % 12].rgb;
}

std::string RegionLegend(const runtime::AssetView& a) {
  if (!a.valid() || !a.asset->regions())
    return "R0 left arm (orange)  R1 right arm (blue)  R2 left leg (green)  R3 right leg (purple)  R4 torso (grey)";
  std::string s;
  const uint32_t n = runtime::RegionCount(a);
  for (uint32_t r = 0; r < n; ++r)
    s += std::string(r ? "  " : "") + RegionSymbol(static_cast<Region>(r)) + " " + runtime::RegionName(a, r) + " (" +
         (runtime::IsTrunkRegion(a, r) ? "grey" : kPalette[r % 12].name) + ")";
  return s;
}

Status ExportDebugGltf(const Mesh& mesh, const runtime::AssetView& a, const std::string& out_path) {
  if (mesh.vertex_count() != a.vertex_count || mesh.triangle_count() != a.triangle_count)
    return MakeError(Error::Code::kConfig, "the mesh (" + std::to_string(mesh.vertex_count()) + " vertices, " +
                                               std::to_string(mesh.triangle_count()) +
                                               " triangles) does not match the asset (" +
                                               std::to_string(a.vertex_count) + ", " + std::to_string(a.triangle_count) + ")");
  const auto* tri_regions = a.asset->triangle_regions();
  // Vertex colours: a vertex takes the region of the last triangle that uses it (seams show as-is).
  std::vector<float> colors(size_t(mesh.vertex_count()) * 3, 0.5f);
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto c = RegionColor(a, RegionAt(tri_regions, t));
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) colors[3 * mesh.indices[3 * t + k] + j] = c[j];
  }
  // Unit UV sphere (12 × 8).
  const int slices = 12, stacks = 8;
  std::vector<float> unit;
  std::vector<uint32_t> unit_idx;
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j <= slices; ++j) {
      const double th = M_PI * i / stacks, ph = 2 * M_PI * j / slices;
      unit.insert(unit.end(), {float(std::sin(th) * std::cos(ph)), float(std::cos(th)), float(std::sin(th) * std::sin(ph))});
    }
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const uint32_t a0 = i * (slices + 1) + j, b0 = a0 + slices + 1;
      unit_idx.insert(unit_idx.end(), {a0, b0, a0 + 1, a0 + 1, b0, b0 + 1});
    }
  std::vector<float> sp_pos, sp_col;
  std::vector<uint32_t> sp_idx;
  const auto* spheres = a.asset->spheres();
  for (uint32_t s = 0; s < a.sphere_count; ++s) {
    const auto* S = spheres->Get(s);
    const auto c = RegionColor(a, RegionAt(a.asset->sphere_regions(), s));
    const uint32_t base = uint32_t(sp_pos.size() / 3);
    for (size_t k = 0; k < unit.size(); k += 3) {
      sp_pos.insert(sp_pos.end(), {S->center().x() + S->radius() * unit[k], S->center().y() + S->radius() * unit[k + 1],
                                   S->center().z() + S->radius() * unit[k + 2]});
      sp_col.insert(sp_col.end(), c.begin(), c.end());
    }
    for (uint32_t i : unit_idx) sp_idx.push_back(base + i);
  }

  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "spherechain export-debug";
  tinygltf::Buffer buffer;
  auto append = [&](const void* data, size_t bytes) {
    const size_t off = buffer.data.size();
    const auto* p = static_cast<const unsigned char*>(data);
    buffer.data.insert(buffer.data.end(), p, p + bytes);
    while (buffer.data.size() % 4) buffer.data.push_back(0);
    return off;
  };
  auto add_view = [&](const void* data, size_t bytes, int target) {
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = append(data, bytes);
    v.byteLength = bytes;
    v.target = target;
    model.bufferViews.push_back(v);
    return int(model.bufferViews.size() - 1);
  };
  auto add_accessor = [&](int view, int comp, size_t count, int type, const std::vector<double>& mn = {},
                          const std::vector<double>& mx = {}) {
    tinygltf::Accessor acc;
    acc.bufferView = view;
    acc.componentType = comp;
    acc.count = count;
    acc.type = type;
    acc.minValues = mn;
    acc.maxValues = mx;
    model.accessors.push_back(acc);
    return int(model.accessors.size() - 1);
  };
  auto bounds = [](const std::vector<float>& p, std::vector<double>* mn, std::vector<double>* mx) {
    *mn = {1e30, 1e30, 1e30};
    *mx = {-1e30, -1e30, -1e30};
    for (size_t i = 0; i < p.size(); ++i) {
      (*mn)[i % 3] = std::min((*mn)[i % 3], double(p[i]));
      (*mx)[i % 3] = std::max((*mx)[i % 3], double(p[i]));
    }
  };
  auto add_mesh = [&](const std::string& name, const std::vector<float>& pos, const std::vector<float>& col,
                      const std::vector<uint32_t>& idx, int material) {
    std::vector<double> mn, mx;
    bounds(pos, &mn, &mx);
    const int pa = add_accessor(add_view(pos.data(), pos.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER),
                                TINYGLTF_COMPONENT_TYPE_FLOAT, pos.size() / 3, TINYGLTF_TYPE_VEC3, mn, mx);
    const int ca = add_accessor(add_view(col.data(), col.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER),
                                TINYGLTF_COMPONENT_TYPE_FLOAT, col.size() / 3, TINYGLTF_TYPE_VEC3);
    const int ia = add_accessor(add_view(idx.data(), idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER),
                                TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, idx.size(), TINYGLTF_TYPE_SCALAR);
    tinygltf::Primitive prim;
    prim.attributes["POSITION"] = pa;
    prim.attributes["COLOR_0"] = ca;
    prim.indices = ia;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.material = material;
    tinygltf::Mesh m;
    m.name = name;
    m.primitives.push_back(prim);
    model.meshes.push_back(m);
    tinygltf::Node n;
    n.name = name;
    n.mesh = int(model.meshes.size() - 1);
    model.nodes.push_back(n);
  };
  tinygltf::Material body;
  body.name = "regions";
  body.pbrMetallicRoughness.metallicFactor = 0.0;
  body.doubleSided = true;
  tinygltf::Material glass;
  glass.name = "spheres";
  glass.alphaMode = "BLEND";
  glass.pbrMetallicRoughness.baseColorFactor = {1.0, 1.0, 1.0, 0.35};
  glass.pbrMetallicRoughness.metallicFactor = 0.0;
  model.materials = {body, glass};
  add_mesh("mesh", mesh.positions, colors, mesh.indices, 0);
  add_mesh("spheres", sp_pos, sp_col, sp_idx, 1);
  model.buffers.push_back(std::move(buffer));
  tinygltf::Scene scene;
  scene.name = "spherechain debug";
  scene.nodes = {0, 1};
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  namespace fs = std::filesystem;
  const fs::path target(out_path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return MakeError(Error::Code::kIo, "folder '" + dir.string() + "' does not exist");
  std::ostringstream text;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, text, /*prettyPrint=*/false, GltfBinary(out_path)))
    return MakeError(Error::Code::kIo, "tinygltf could not serialise the debug scene");
  return import::WriteFileAtomic(out_path, text.str());
}

namespace {

/// What one picture shows: per-triangle colours of the two panels of a view (left: `tri_left`,
/// right: `tri_right` + the spheres), over the mesh at `positions` (#V×3).
struct Picture {
  const float* positions = nullptr;
  std::function<std::array<float, 3>(uint32_t)> tri_left, tri_right;
  std::vector<FrameSphere> spheres;
  const char* left_name = "regions";
  const char* right_name = "spheres";
  std::string caption;
};

std::string RenderSvg(const Mesh& mesh, const runtime::AssetView& a, const Picture& pic, int width_px) {
  const Frame f = CharacterFrame(mesh, a);
  auto P = [&](uint32_t v) {
    return Eigen::Vector3f(pic.positions[3 * size_t{v}], pic.positions[3 * size_t{v} + 1], pic.positions[3 * size_t{v} + 2]);
  };
  // Views (camera right = view direction × up): front, camera in front looking back, so screen x =
  // the character's left (its left arm on the viewer's right); side, camera at the character's left
  // looking across, so screen x = −front (the character faces the viewer's left).
  struct View { Eigen::Vector3f sx, sy, toward_viewer; const char* name; };
  // A creature lies along `front`: its side first, then end-on. A biped (the paper's five regions, or
  // the extended layout) stands: front, then side.
  const bool creature = a.asset->regions() != nullptr && !a.asset->biped();
  const View views[2] = {creature ? View{-f.front, f.up, f.left, "side"} : View{f.left, f.up, f.front, "front"},
                         creature ? View{f.left, f.up, f.front, "end-on (along the trunk)"}
                                  : View{-f.front, f.up, f.left, "side (character's left)"}};
  // One scale for every panel, the largest at which each view's projection (mesh and spheres) fits its
  // panel (a T-pose or wide arms included); each view centred on its own projected extent.
  const int panel = width_px / 4, height = int(panel * (creature ? 1.0f : 1.9f));
  Eigen::Vector2f lo2[2], hi2[2];
  float scale = 1e30f;
  for (int vi = 0; vi < 2; ++vi) {
    lo2[vi] = Eigen::Vector2f::Constant(1e30f);
    hi2[vi] = Eigen::Vector2f::Constant(-1e30f);
    auto extend = [&](const Eigen::Vector3f& p, float r) {
      const Eigen::Vector2f q(p.dot(views[vi].sx), p.dot(views[vi].sy));
      lo2[vi] = lo2[vi].cwiseMin(q - Eigen::Vector2f::Constant(r));
      hi2[vi] = hi2[vi].cwiseMax(q + Eigen::Vector2f::Constant(r));
    };
    for (uint32_t v = 0; v < mesh.vertex_count(); ++v) extend(P(v), 0.0f);
    for (const FrameSphere& S : pic.spheres) extend(Eigen::Vector3f(S.center.data()), S.radius);
    const Eigen::Vector2f e = (hi2[vi] - lo2[vi]).cwiseMax(Eigen::Vector2f::Constant(1e-12f));
    scale = std::min({scale, 0.94f * float(panel) / e.x(), 0.92f * float(height) / e.y()});
  }

  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << panel * 4 << "' height='" << height + 40
      << "' viewBox='0 0 " << panel * 4 << ' ' << height + 40 << "'>\n<rect width='100%' height='100%' fill='white'/>\n";
  svg.setf(std::ios::fixed);
  svg.precision(1);
  for (int vi = 0; vi < 2; ++vi) {
    const View& V = views[vi];
    const Eigen::Vector2f mid = 0.5f * (lo2[vi] + hi2[vi]);
    auto project = [&](const Eigen::Vector3f& p, float ox) {
      return Eigen::Vector2f(ox + panel * 0.5f + scale * (p.dot(V.sx) - mid.x()),
                             20 + height * 0.5f - scale * (p.dot(V.sy) - mid.y()));
    };
    // Triangles far → near.
    std::vector<uint32_t> order(mesh.triangle_count());
    std::iota(order.begin(), order.end(), 0u);
    std::vector<float> depth(order.size());
    for (uint32_t t : order)
      depth[t] = (P(mesh.indices[3 * t]) + P(mesh.indices[3 * t + 1]) + P(mesh.indices[3 * t + 2])).dot(V.toward_viewer);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return depth[x] < depth[y]; });
    for (int pass = 0; pass < 2; ++pass) {
      const float ox = float(panel * (2 * vi + pass));
      svg << "<g>\n";
      for (uint32_t t : order) {
        const Eigen::Vector3f p0 = P(mesh.indices[3 * t]), p1 = P(mesh.indices[3 * t + 1]), p2 = P(mesh.indices[3 * t + 2]);
        const Eigen::Vector3f n = (p1 - p0).cross(p2 - p0);
        const float nn = n.norm();
        if (nn <= 0) continue;
        const float lambert = std::abs(n.dot(V.toward_viewer)) / nn;
        const auto col = pass == 0 ? pic.tri_left(t) : pic.tri_right(t);
        const std::string fill = Hex(col, 0.35f + 0.65f * lambert);
        const Eigen::Vector2f a2 = project(p0, ox), b2 = project(p1, ox), c2 = project(p2, ox);
        svg << "<path d='M" << a2.x() << ',' << a2.y() << 'L' << b2.x() << ',' << b2.y() << 'L' << c2.x() << ','
            << c2.y() << "Z' fill='" << fill << "' stroke='" << fill << "' stroke-width='0.3'/>\n";
      }
      svg << "</g>\n";
      if (pass == 1) {
        std::vector<uint32_t> so(pic.spheres.size());
        std::iota(so.begin(), so.end(), 0u);
        auto sdepth = [&](uint32_t s) { return Eigen::Vector3f(pic.spheres[s].center.data()).dot(V.toward_viewer); };
        std::stable_sort(so.begin(), so.end(), [&](uint32_t x, uint32_t y) { return sdepth(x) < sdepth(y); });
        for (uint32_t s : so) {
          const FrameSphere& S = pic.spheres[s];
          const Eigen::Vector2f c2 = project(Eigen::Vector3f(S.center.data()), ox);
          svg << "<circle cx='" << c2.x() << "' cy='" << c2.y() << "' r='" << scale * S.radius << "' fill='"
              << Hex(S.color) << "' fill-opacity='" << S.opacity << "' stroke='" << Hex(S.color, 0.6f)
              << "' stroke-width='" << (S.opacity > 0.5f ? 2 : 1) << "'/>\n";
        }
      }
      // A title fits its panel: 14 px, smaller when it is long for the panel (sans-serif glyphs average about
      // 0.56 em; a creature's end-on title beside a narrow panel of a 1,200 px picture overran the next one).
      const std::string title = std::string(V.name) + ": " + (pass == 0 ? pic.left_name : pic.right_name);
      const float title_px = std::min(14.0f, float(panel - 14) / (0.56f * float(std::max<size_t>(1, title.size()))));
      svg << "<text x='" << ox + 10 << "' y='16' font-family='sans-serif' font-size='" << title_px << "'>"
          << XmlEscape(title) << "</text>\n";
    }
  }
  svg << "<text x='10' y='" << height + 32 << "' font-family='sans-serif' font-size='13'>" << XmlEscape(pic.caption)
      << "</text>\n</svg>\n";
  return svg.str();
}

}  // namespace

std::string RenderDebugSvg(const Mesh& mesh, const runtime::AssetView& a, int width_px) {
  const auto* tri_regions = a.asset->triangle_regions();
  const auto* spheres = a.asset->spheres();
  const auto* sphere_regions = a.asset->sphere_regions();
  Picture pic;
  pic.positions = mesh.positions.data();
  pic.tri_left = [&](uint32_t t) { return RegionColor(a, RegionAt(tri_regions, t)); };
  pic.tri_right = [](uint32_t) { return std::array<float, 3>{0.85f, 0.85f, 0.85f}; };
  for (uint32_t s = 0; s < a.sphere_count; ++s) {
    const auto* S = spheres->Get(s);
    pic.spheres.push_back({{S->center().x(), S->center().y(), S->center().z()}, S->radius(),
                           RegionColor(a, RegionAt(sphere_regions, s)), 0.45f});
  }
  pic.caption = RegionLegend(a) + " — " + std::to_string(a.sphere_count) + " spheres";
  return RenderSvg(mesh, a, pic, width_px);
}

std::string RenderFrameSvg(const Mesh& mesh, const runtime::AssetView& a, const float* positions,
                           const std::vector<FrameSphere>& spheres, const std::vector<uint8_t>& triangle_marks,
                           const std::string& caption, int width_px) {
  const auto* tri_regions = a.asset->triangle_regions();
  Picture pic;
  pic.positions = positions;
  auto marked = [&](uint32_t t, std::array<float, 3> otherwise) {
    const uint8_t m = t < triangle_marks.size() ? triangle_marks[t] : 0;
    return m == 1 ? std::array<float, 3>{0.95f, 0.05f, 0.05f} : m == 2 ? std::array<float, 3>{1.0f, 0.75f, 0.0f} : otherwise;
  };
  pic.tri_left = [&](uint32_t t) {
    return marked(t, tri_regions ? RegionColor(a, tri_regions->Get(t)) : std::array<float, 3>{0.8f, 0.8f, 0.8f});
  };
  pic.tri_right = [&](uint32_t t) { return marked(t, {0.85f, 0.85f, 0.85f}); };
  pic.spheres = spheres;
  pic.left_name = "regions + contacts";
  pic.right_name = "contacts + spheres";
  pic.caption = caption;
  return RenderSvg(mesh, a, pic, width_px);
}

Result<std::string> SvgToPngBytes(const std::string& svg, const std::string& for_path) {
  // rsvg-convert -f png, without a shell: the SVG on its standard input (a socket, so that a write to it after it
  // ended is an error, not a SIGPIPE), the PNG read from its standard output.
  const std::string what = for_path.empty() ? std::string("a picture") : "'" + for_path + "'";
  int in[2], out[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, in) != 0)
    return MakeError(Error::Code::kIo, "cannot start rsvg-convert for " + what + ": " + std::strerror(errno));
  if (::pipe2(out, O_CLOEXEC) != 0) {
    const int e = errno;
    ::close(in[0]), ::close(in[1]);
    return MakeError(Error::Code::kIo, "cannot start rsvg-convert for " + what + ": " + std::strerror(e));
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[1], 0);  // dup2 clears close-on-exec on 0 and 1 only
  posix_spawn_file_actions_adddup2(&actions, out[1], 1);
  std::string a0 = "rsvg-convert", a1 = "-f", a2 = "png";
  char* argv[] = {a0.data(), a1.data(), a2.data(), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, "rsvg-convert", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(in[1]);
  ::close(out[1]);
  std::string png;
  if (spawned == 0) {
    size_t sent = 0;
    bool writing = true, reading = true;
    if (svg.empty()) ::shutdown(in[0], SHUT_WR), writing = false;
    while (reading) {
      pollfd p[2] = {{out[0], POLLIN, 0}, {writing ? in[0] : -1, POLLOUT, 0}};
      if (::poll(p, 2, -1) < 0) {
        if (errno == EINTR) continue;
        break;
      }
      if (writing && p[1].revents) {
        const ssize_t n = ::send(in[0], svg.data() + sent, svg.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n > 0) sent += static_cast<size_t>(n);
        if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) writing = false;  // it stopped reading
        if (sent == svg.size()) ::shutdown(in[0], SHUT_WR), writing = false;
      }
      if (p[0].revents) {
        char buf[1 << 16];
        const ssize_t n = ::read(out[0], buf, sizeof buf);
        if (n > 0) png.append(buf, static_cast<size_t>(n));
        else if (n == 0 || errno != EINTR) reading = false;
      }
    }
  }
  ::close(in[0]);
  ::close(out[0]);
  int status = 0;
  if (spawned != 0)
    return MakeError(Error::Code::kIo, "rsvg-convert is not installed (Debian librsvg2-bin), needed to write " + what +
                                           ": " + std::strerror(spawned));
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || png.empty())
    return MakeError(Error::Code::kIo, "rsvg-convert could not render the picture for " + what + " (" +
                                           (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                                              : "signal " + std::to_string(WTERMSIG(status))) +
                                           "; its message is above)");
  return png;
}

Status SvgToPng(const std::string& svg, const std::string& png_path, bool keep_svg) {
  auto png = SvgToPngBytes(svg, png_path);
  if (!png.ok()) return png.error();
  if (keep_svg)  // an output beside the PNG
    if (Status s = import::WriteFileAtomic(png_path + ".svg", svg); !s.ok()) return s;
  return import::WriteFileAtomic(png_path, png.value());
}

Status RenderDebugPng(const Mesh& mesh, const runtime::AssetView& a, const std::string& png_path, bool keep_svg) {
  return SvgToPng(RenderDebugSvg(mesh, a), png_path, keep_svg);
}

std::string RegionLegendLine(const runtime::AssetView& view) {
  if (!view.valid() || !view.asset->regions()) return {};
  std::string s = "regions:";
  const uint32_t n = runtime::RegionCount(view);
  for (uint32_t r = 0; r < n; ++r)
    s += std::string(r ? ", R" : " R") + std::to_string(r) + " " + runtime::RegionName(view, r) +
         (runtime::IsTrunkRegion(view, r) ? " (trunk)" : "");
  return s;
}

std::string RegionPairName(const runtime::AssetView& view, int a, int b) {
  std::string s = "R" + std::to_string(a) + "-R" + std::to_string(b);
  if (view.valid() && view.asset->regions() && a >= 0 && b >= 0)
    s += std::string(" (") + runtime::RegionName(view, uint32_t(a)) + "-" + runtime::RegionName(view, uint32_t(b)) + ")";
  return s;
}

namespace {

// The length of the well-formed UTF-8 sequence at s[i] (1–4), or 0 when none starts there.
size_t Utf8SequenceAt(const std::string& s, size_t i) {
  const auto byte = [&](size_t k) { return k < s.size() ? static_cast<unsigned char>(s[k]) : 0u; };
  const unsigned b0 = byte(i);
  const auto cont = [&](size_t k, unsigned lo, unsigned hi) { return byte(k) >= lo && byte(k) <= hi; };
  if (b0 < 0x80) return 1;
  if (b0 >= 0xC2 && b0 <= 0xDF) return cont(i + 1, 0x80, 0xBF) ? 2 : 0;
  if (b0 >= 0xE0 && b0 <= 0xEF) {
    const unsigned lo = b0 == 0xE0 ? 0xA0 : 0x80, hi = b0 == 0xED ? 0x9F : 0xBF;
    return cont(i + 1, lo, hi) && cont(i + 2, 0x80, 0xBF) ? 3 : 0;
  }
  if (b0 >= 0xF0 && b0 <= 0xF4) {
    const unsigned lo = b0 == 0xF0 ? 0x90 : 0x80, hi = b0 == 0xF4 ? 0x8F : 0xBF;
    return cont(i + 1, lo, hi) && cont(i + 2, 0x80, 0xBF) && cont(i + 3, 0x80, 0xBF) ? 4 : 0;
  }
  return 0;
}

}  // namespace

namespace detail {

std::string ValidUtf8(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (size_t i = 0; i < s.size();) {
    const size_t n = Utf8SequenceAt(s, i);
    if (n == 0) {
      o += "\xEF\xBF\xBD";  // U+FFFD
      ++i;
    } else {
      o.append(s, i, n);
      i += n;
    }
  }
  return o;
}

}  // namespace detail

bool GltfBinary(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".glb";
}

std::string XmlEscape(const std::string& s) {
  std::string o;
  o.reserve(s.size());
  for (const char c : detail::ValidUtf8(s)) {  // bytes >= 0x80 are then whole characters: kept as they are
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      case '\'': o += "&apos;"; break;
      case '\n': o += "&#10;"; break;
      default:
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t') o += c;  // XML 1.0 forbids other controls
    }
  }
  return o;
}

}  // namespace spherechain::playback
