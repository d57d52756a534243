// spherechain import — the data every stage shares: the imported character (Mesh, Skin, Clip), the
// regions (the paper's five, or a creature's RegionLayout), Result<T> for fallible calls, and the
// injected Context for logs and stage timers.
//
// The baker library never prints: it logs through Context (the CLI routes it to spdlog), and every
// call that reads user data returns Result<T>; exceptions from assimp, tinygltf or CGAL are caught at
// the stage boundary and turned into Error messages.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace spherechain::import {

// ---------------------------------------------------------------------------------------------------
// Regions (paper §3): R0 left arm, R1 right arm, R2 left leg, R3 right leg, R4 torso. Left/right is the
// character's own. Head and neck belong to the torso, hands to the arms, feet to the legs. A creature
// (the any-skeleton path) has its own regions — a RegionLayout below —, whose values are Region values too.
enum class Region : uint8_t { kLeftArm = 0, kRightArm = 1, kLeftLeg = 2, kRightLeg = 3, kTorso = 4 };
inline constexpr int kRegionCount = 5;
/// Sentinel for "no region" in per-triangle / per-vertex region arrays.
inline constexpr uint8_t kNoRegion = 0xFF;

/// "left_arm", "right_arm", "left_leg", "right_leg", "torso"; "none" for anything else (the paper's
/// names; a creature's regions are named by its RegionLayout).
const char* RegionName(Region r);
/// "R0".."R31" (the region value as a symbol, any layout); "R?" past kMaxRegions.
const char* RegionSymbol(Region r);
inline bool IsTubular(Region r) { return r != Region::kTorso; }

/// Most regions a layout holds (region values are bytes; kNoRegion = 0xFF marks none). The any-skeleton
/// path refuses a creature with more limbs than kMaxRegions − 1.
inline constexpr int kMaxRegions = 32;

/// What a region is: a limb (tubular: its spheres form a sequence from where it joins the trunk
/// outwards) or the trunk (the paper's torso; one per layout, the last region).
enum class RegionKind : uint8_t { kLimb = 0, kTrunk = 1 };

/// One region of a RegionLayout.
struct RegionInfo {
  std::string name;  ///< "left_arm" ... "torso" (paper); any-skeleton: from its bones ("HindLeg_L", "Tail"), "trunk"
  RegionKind kind = RegionKind::kLimb;
  int mirror = -1;   ///< the region on the other side of a left/right pair, or −1 (balance checks)
  std::string bone;  ///< [opt] any-skeleton: the limb's first bone (the trunk: the bone joining its junctions)
  /// The region a limb hangs off: −1 the trunk (every paper limb, every creature limb); a human's
  /// extended layout (RegionLayout::Extended) hangs each hand off its arm and each foot off its leg.
  /// Junction planes, limb roots (the sequence's start), the crease exclusions and the attachment check
  /// look at the limb's parent.
  int parent = -1;
  /// The region whose volume share weighs this one's in the cover fit's greedy (FitParams::region_balance):
  /// −1 its own; the extended layout's head, hands and feet take the torso's, arm's and leg's, so the
  /// budget goes where it went on the paper's five regions. Baker-only (not in the asset).
  int volume_group = -1;
};

/// The regions of a body and what each is. Region values (Segmentation::triangle_regions,
/// FittedSphere::region, schema Asset.sphere_regions) index `regions`; the trunk is always the last.
/// Default-constructed: the paper's five (R0 left arm, R1 right arm, R2 left leg, R3 right leg, R4 torso).
/// The any-skeleton path (segment.h SegmentBySkeleton) builds a creature's: limbs R0..R(n−2), trunk R(n−1).
struct RegionLayout {
  std::vector<RegionInfo> regions = PaperRegions();
  /// true for a standing biped — the paper's five regions, or the extended layout with head, hands and
  /// feet (RegionLayout::Extended): torso along Mesh::up_axis, Table 1's chains (extended), torso labels
  /// L/R/T/D; false for a creature's layout.
  bool paper = true;
  /// Creature layouts: the trunk's principal axis (unit; bind pose, model space), which plays the part
  /// of the up axis for the trunk (sphere order, side-by-side exclusions, pivots). Paper: unused (zero).
  std::array<double, 3> trunk_axis{0.0, 0.0, 0.0};

  /// Number of regions (5 for the paper's; 3..kMaxRegions for a creature's).
  int count() const { return static_cast<int>(regions.size()); }
  /// The trunk (the paper's R4 torso): always the last region.
  Region trunk() const { return static_cast<Region>(regions.size() - 1); }
  /// True for the trunk.
  bool IsTrunk(Region r) const { return static_cast<int>(r) == count() - 1; }
  /// True for a limb (any region before the trunk).
  bool IsLimb(Region r) const { return static_cast<int>(r) < count() - 1; }
  /// regions[r].name, or "none" for a value outside the layout.
  const char* Name(Region r) const {
    return static_cast<int>(r) < count() ? regions[static_cast<size_t>(r)].name.c_str() : "none";
  }
  /// The region limb `r` hangs off (RegionInfo::parent; the trunk when −1).
  Region Parent(Region r) const {
    const int p = static_cast<int>(r) < count() ? regions[static_cast<size_t>(r)].parent : -1;
    return p >= 0 ? static_cast<Region>(p) : trunk();
  }
  /// The paper's five regions, unchanged (schema v3 assets describe no layout: these are implied).
  bool IsPaperFive() const { return paper && count() == 5; }
  /// The region named `name`, or −1.
  int Find(const std::string& name) const {
    for (int k = 0; k < count(); ++k)
      if (regions[static_cast<size_t>(k)].name == name) return k;
    return -1;
  }
  /// The paper's five regions (limbs mirrored 0↔1, 2↔3; the torso last).
  static std::vector<RegionInfo> PaperRegions();
};

// ---------------------------------------------------------------------------------------------------
/// An error a caller can show a user: a stable code and a message that says what and where.
struct Error {
  enum class Code : uint8_t {
    kIo,            ///< missing / unreadable / unwritable file
    kFormat,        ///< unsupported or corrupt file format
    kInvalidMesh,   ///< no triangles, NaN/Inf, out-of-range indices, ...
    kSegmentation,  ///< not a standing body / a region could not be found
    kFit,           ///< sphere fitting failed
    kConfig,        ///< bad bake configuration
    kInternal,      ///< a library threw; message holds its text
    kImplausible,   ///< a plausibility check failed (plausibility.h): the bake looks wrong; nothing written
  };
  Code code = Code::kInternal;
  std::string message;
};
const char* ToString(Error::Code code);
/// "<kind>: <message>" (ToString(code), then the message): what the CLI prints after "error: ".
std::string ToString(const Error& error);

/// Value or Error (Jolt's Result<T>). Check `ok()` before `value()`.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}           // NOLINT(google-explicit-constructor)
  Result(Error error) : v_(std::move(error)) {}       // NOLINT(google-explicit-constructor)
  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }
  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  const Error& error() const { return std::get<1>(v_); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

 private:
  std::variant<T, Error> v_;
};

/// Result<void>.
struct Ok {};
using Status = Result<Ok>;

inline Error MakeError(Error::Code code, std::string message) { return Error{code, std::move(message)}; }

// ---------------------------------------------------------------------------------------------------
/// Injected logging, per-stage timing (Recast's rcContext) and the record of the files read. All members
/// optional; not thread-safe (one Context per bake: concurrent bakes each take their own).
class Context {
 public:
  enum class Level : uint8_t { kDebug, kInfo, kWarn };
  std::function<void(Level, const std::string&)> sink;  ///< [opt] receives every log line
  std::vector<std::pair<std::string, double>> timings_ms;  ///< stage name → milliseconds, in order
  /// Every file the work done with this Context read, in the order first read, each once: absolute and
  /// lexically normal (symbolic links kept as named). Recorded where files are opened — the glTF reader's
  /// file callbacks (the .gltf/.glb, external buffers and images), assimp's file system (the input and
  /// every file its importer opens), the OBJ and MakeHuman rig readers (.obj, .mhskel, .mhw), the bake
  /// configuration and region-map readers — and only for files that were opened and read. What `spherechain
  /// bake --depfile` writes (import/file_io.h MakeDepfile); a build system rebakes when one of them changes.
  std::vector<std::string> files_read;

  /// Adds `path` to files_read (made absolute against the current directory; a path already there is not
  /// added again). Called by the readers after they opened `path`. Allocates.
  void RecordFileRead(const std::string& path);

  void Log(Level level, const std::string& message) const {
    if (sink) sink(level, message);
  }
  void Info(const std::string& m) const { Log(Level::kInfo, m); }
  void Warn(const std::string& m) const { Log(Level::kWarn, m); }
  void Debug(const std::string& m) const { Log(Level::kDebug, m); }

  /// RAII stage timer: adds (name, ms) to `timings_ms` when it goes out of scope.
  class Timer {
   public:
    Timer(Context* ctx, std::string name)
        : ctx_(ctx), name_(std::move(name)), t0_(std::chrono::steady_clock::now()) {}
    ~Timer() {
      if (!ctx_) return;
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
      ctx_->timings_ms.emplace_back(name_, ms);
    }
    Timer(const Timer&) = delete;
    Timer& operator=(const Timer&) = delete;

   private:
    Context* ctx_;
    std::string name_;
    std::chrono::steady_clock::time_point t0_;
  };
};

// ---------------------------------------------------------------------------------------------------
// The imported character.

enum class UpAxis : uint8_t { kY = 0, kZ = 1, kX = 2 };

/// One source mesh / glTF primitive, in concatenation order (documented per importer in import.h).
struct MeshPart {
  std::string name;
  uint32_t first_vertex = 0;
  uint32_t vertex_count = 0;
  uint32_t first_triangle = 0;
  uint32_t triangle_count = 0;
};

/// A node of the skeleton hierarchy with its rest (bind-time) local transform.
/// Nodes are stored parents-first: `parent < own index`, or -1 for a root.
struct Node {
  std::string name;
  int32_t parent = -1;
  std::array<float, 3> translation{0, 0, 0};
  std::array<float, 4> rotation{0, 0, 0, 1};  ///< unit quaternion (x, y, z, w)
  std::array<float, 3> scale{1, 1, 1};
};

/// A skinning influence: the node it follows and the matrix taking *assembled bind-pose model space*
/// (the space of Mesh::positions) into that node's space. Several joints may share a node (one per
/// source mesh that the bone skins, each with its own inverse bind).
struct SkinJoint {
  int32_t node = -1;
  std::array<float, 16> inverse_bind{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  ///< column-major
};

/// Skin weights in compressed rows: vertex v's influences are
/// [weight_offsets[v], weight_offsets[v+1]) into weight_joints / weights. Weights of a vertex sum to 1
/// (the importer normalises); a vertex with no influence follows no joint (stays at bind).
struct Skin {
  std::vector<Node> nodes;
  std::vector<SkinJoint> joints;
  std::vector<uint32_t> weight_offsets;  ///< \#V+1
  std::vector<uint32_t> weight_joints;   ///< index into joints
  std::vector<float> weights;
  std::string source;  ///< "gltf", "assimp", "mhskel"
};

/// One animation channel (glTF semantics): node, property, key times (s) and values (3 or 4 floats a
/// key; rotations are quaternions x, y, z, w).
struct Channel {
  enum class Path : uint8_t { kTranslation, kRotation, kScale };
  enum class Interpolation : uint8_t { kLinear, kStep };
  int32_t node = -1;
  Path path = Path::kRotation;
  Interpolation interpolation = Interpolation::kLinear;
  std::vector<float> times;
  std::vector<float> values;
};

struct Clip {
  std::string name;
  float duration_s = 0.0f;
  std::vector<Channel> channels;
};

/// The character as imported. Positions are the assembled bind pose (node transforms applied) in
/// model space and source units; vertex and triangle order are the source's (parts concatenated).
struct Mesh {
  std::vector<float> positions;  ///< \#V×3
  std::vector<uint32_t> indices;  ///< \#T×3, counter-clockwise as in the source
  std::vector<MeshPart> parts;
  std::string source_path;
  std::string source_format;  ///< "gltf", "obj", "x", "fbx", ...
  std::string units = "unknown";  ///< "dm", "m", "cm", ... when the source says or the importer knows
  float unit_scale_m = 0.0f;      ///< metres per unit, 0 when unknown
  UpAxis up_axis = UpAxis::kY;
  std::optional<Skin> skin;
  std::vector<Clip> clips;
  /// The vertex contract the importer applied (import.h VertexContract): "joined" or "source" for the
  /// assimp formats, "file" for glTF / OBJ (the file's own buffer, which is what engines upload).
  std::string vertex_contract = "file";
  /// assimp formats: \#V under each contract (the same file read both ways); 0 for the other formats.
  /// Lets a mismatch message say which contract a game's buffer looks like (Asset.*_vertex_count).
  uint32_t source_vertex_count = 0;
  uint32_t joined_vertex_count = 0;

  uint32_t vertex_count() const { return static_cast<uint32_t>(positions.size() / 3); }
  uint32_t triangle_count() const { return static_cast<uint32_t>(indices.size() / 3); }
};

}  // namespace spherechain::import
