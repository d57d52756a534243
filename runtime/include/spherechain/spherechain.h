/* spherechain — C API of the runtime (C99). Link spherechain::c (the shared library libspherechain_c). */
/// @file spherechain.h
/// The C API of the spherechain runtime: the C++ runtime (`spherechain/runtime/`) behind a C99 header, in a
/// shared library (`libspherechain_c`, CMake target `spherechain::c`) that exports only the `sc_*` symbols.
///
/// Conventions, for every function below:
/// - Every fallible call returns an ::sc_status; nothing throws, nothing prints. ::sc_status_string names it.
/// - Only sc_model_create() and sc_workspace_create() allocate; every per-frame call (refit, detect, narrow
///   phase) writes into memory the caller owns and sizes once (sc_detect_bound(); the narrow phase reports
///   the full count when a buffer was too small).
/// - Pointers are non-null unless marked [opt]. A null required pointer gives #SC_ERROR_NULL_ARGUMENT and
///   writes nothing but the documented failure values of the outputs given (`*count = 0`, `*out = NULL`).
/// - A model is immutable after creation: any number of workspaces and threads may use it at once. A workspace
///   is one character: one call at a time per workspace; different workspaces run in parallel.
/// - Every per-frame call takes the model and the workspace: a workspace made for another model gives
///   #SC_ERROR_WORKSPACE_MODEL and writes nothing.
/// - Units and space are those of the asset (its source units, model space at bind pose) or of any rigid
///   motion of it (world space works: spheres, depths and directions come out in that space).
///
/// @code
///   sc_model* model;  sc_status s = sc_model_create(bytes, size, SC_MODEL_NARROW_PHASE, &model);  // per asset
///   sc_workspace* ws; s = sc_workspace_create(model, &ws);                                        // per character
///   sc_pair* pairs = malloc(sizeof(sc_pair) * sc_detect_bound(model, SC_DETECT_M2));  // once (32-bit: see the bound)
///   uint32_t n;
///   // every frame:
///   s = sc_refit_vertices(model, ws, vertex_buffer, vertex_count, sizeof(my_vertex));
///   s = sc_detect(model, ws, SC_DETECT_M2, -1.0f, pairs, sc_detect_bound(model, SC_DETECT_M2), &n);
/// @endcode
#ifndef SPHERECHAIN_SPHERECHAIN_H
#define SPHERECHAIN_SPHERECHAIN_H

#include <stddef.h>
#include <stdint.h>

/// Marks a symbol of the C API's shared library: exported when building it (SPHERECHAIN_C_BUILD), imported
/// otherwise (Windows); default visibility on GCC/Clang, whose builds hide every other symbol.
#if defined(_WIN32) || defined(__CYGWIN__)
#if defined(SPHERECHAIN_C_BUILD)
#define SC_API __declspec(dllexport)
#else
#define SC_API __declspec(dllimport)
#endif
#elif defined(__GNUC__) && __GNUC__ >= 4
#define SC_API __attribute__((visibility("default")))
#else
#define SC_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- status ------------------------------------------------------------------------------------------ */

/// Outcome of every fallible call, the runtime's `spherechain::runtime::Status` value for value (Recast
/// style): bit 31 set = failure (#SC_FAILED); a success may carry the detail "output truncated"
/// (#SC_OK_TRUNCATED). Compare with the `SC_*` constants; ::sc_status_string names every value.
typedef uint32_t sc_status;

/// True (1) for #SC_OK and every success with detail (#SC_OK_TRUNCATED).
#define SC_SUCCEEDED(s) ((((uint32_t)(s)) & 0x80000000u) == 0u)
/// True (1) for every `SC_ERROR_*`.
#define SC_FAILED(s) (!SC_SUCCEEDED(s))

#define SC_OK ((sc_status)0x00000000u)            ///< Success, outputs complete.
#define SC_OK_TRUNCATED ((sc_status)0x00000001u)  ///< Success, but the caller's output buffer was too small:
                                                  ///< it holds the first `capacity` records, `*count` the full count.
#define SC_ERROR_NULL_ARGUMENT ((sc_status)0x80000001u)  ///< A required pointer was null (nothing written).
#define SC_ERROR_ALIGNMENT ((sc_status)0x80000002u)      ///< Asset bytes not 8-byte aligned, or positions /
                                                         ///< matrices not 4-byte aligned.
#define SC_ERROR_INVALID_JOB ((sc_status)0x80000003u)    ///< Arguments inconsistent: unknown method, flag or
                                                         ///< exclusions; a margin or crease not allowed; the
                                                         ///< narrow phase on a model created without it.
#define SC_ERROR_VERTEX_COUNT ((sc_status)0x80000004u)   ///< vertex_count differs from the asset's \#V.
#define SC_ERROR_STRIDE ((sc_status)0x80000005u)         ///< stride_bytes < 12, not a multiple of 4, or >= 2^32.
#define SC_ERROR_OUT_OF_MEMORY ((sc_status)0x80000006u)  ///< A model or workspace allocation failed.
#define SC_ERROR_NON_FINITE_POSITIONS ((sc_status)0x80000007u)  ///< The narrow phase read a NaN or infinite position.
#define SC_ERROR_JOINT_COUNT ((sc_status)0x80000008u)    ///< joint_count differs from the asset's \#J.
#define SC_ERROR_NON_FINITE_JOINTS ((sc_status)0x80000009u)  ///< A joint matrix holds a NaN or an infinity.
#define SC_ERROR_WORKSPACE_MODEL ((sc_status)0x8000000Au)    ///< The workspace was made for another model.
#define SC_ERROR_BUFFER_TOO_SMALL ((sc_status)0x8000000Bu)   ///< Caller memory too small (runtime InitInPlace;
                                                             ///< no C function returns it).
#define SC_ERROR_FRAME_TANGLED ((sc_status)0x8000000Cu)      ///< sc_narrow_phase: the frame's skin
                                                             ///< passes through itself beyond the budget (positions
                                                             ///< that are no pose of the character); count 0.
#define SC_ERROR_ASSET_TOO_SMALL ((sc_status)0x80000101u)  ///< Fewer bytes than a FlatBuffer header (8): truncated.
#define SC_ERROR_ASSET_TOO_LARGE ((sc_status)0x80000102u)  ///< More than 1 GiB.
#define SC_ERROR_IDENTIFIER ((sc_status)0x80000103u)       ///< Not a .sphc asset (file_identifier is not "SPHC").
#define SC_ERROR_VERSION_TOO_OLD ((sc_status)0x80000104u)  ///< Asset older than this SDK reads: re-bake.
#define SC_ERROR_VERSION_TOO_NEW ((sc_status)0x80000105u)  ///< Asset from a newer SDK.
#define SC_ERROR_CORRUPT ((sc_status)0x80000106u)          ///< The FlatBuffers verifier rejected the bytes.
#define SC_ERROR_MISSING_FIELD ((sc_status)0x80000201u)    ///< A field the call needs is absent from the asset.
#define SC_ERROR_NO_SPHERES ((sc_status)0x80000202u)       ///< The asset has no spheres.
#define SC_ERROR_TOO_MANY_SPHERES ((sc_status)0x80000203u) ///< More than 65,535 spheres.
#define SC_ERROR_TOO_MANY_CHAINS ((sc_status)0x80000204u)  ///< More than 32 chains, or too many pairs in them.
#define SC_ERROR_COUNT_MISMATCH ((sc_status)0x80000205u)   ///< An asset array's length disagrees with \#S, \#T or \#V.
#define SC_ERROR_INDEX_OUT_OF_RANGE ((sc_status)0x80000206u)  ///< A sphere, triangle, vertex or joint index out of
                                                              ///< range, or more than 65,536 joints (in the asset),
                                                              ///< or a sphere argument >= \#S.
#define SC_ERROR_OFFSETS ((sc_status)0x80000207u)          ///< Region offsets malformed in the asset.
#define SC_ERROR_NON_FINITE ((sc_status)0x80000208u)       ///< A NaN or infinite float in the asset.
#define SC_ERROR_RADIUS ((sc_status)0x80000209u)           ///< A sphere radius <= 0 in the asset.
#define SC_ERROR_PIVOT_FRAME ((sc_status)0x8000020Au)      ///< A pivot frame's mean distance <= 0 (or too small
                                                           ///< for its radius) in the asset.
#define SC_ERROR_CHAIN_ORDER ((sc_status)0x8000020Bu)      ///< A chain's spheres not strictly ascending.
#define SC_ERROR_EXCLUDED_PAIRS ((sc_status)0x8000020Cu)   ///< Excluded pairs not a < b or not strictly ascending.
#define SC_ERROR_CONTACT_MARGIN ((sc_status)0x8000020Du)   ///< The asset's contact margin is negative.
#define SC_ERROR_SKIN_WEIGHTS ((sc_status)0x8000020Eu)     ///< A sphere's joint weights negative, not finite,
                                                           ///< one after a 0, or not summing to 1.
#define SC_ERROR_REGIONS ((sc_status)0x8000020Fu)          ///< The asset's regions malformed.
#define SC_ERROR_BIND_POSE_TANGLED ((sc_status)0x80000301u)  ///< The narrow phase's model: the bind pose passes
                                                            ///< through itself beyond its budget (a broken mesh).
#define SC_ERROR_CREASE_TOO_WIDE ((sc_status)0x80000302u)    ///< The narrow phase's model: the crease reaches too
                                                            ///< much of the bind surface from each vertex (a
                                                            ///< collapsed bind pose, or a mesh far denser than
                                                            ///< its crease: re-bake with a smaller crease_rel).

/// Static, NUL-terminated English text of `status`, starting with its constant's name (e.g.
/// "SC_ERROR_VERSION_TOO_NEW: asset schema_version is newer than this SDK"); "unknown status" for a value
/// that is none of them. Never null. Lifetime: static. Thread-safe, O(1).
SC_API const char* sc_status_string(sc_status status);

/* ---- versions ---------------------------------------------------------------------------------------- */

/// The SDK version this header belongs to (the project's version, CMake `PROJECT_VERSION`): major, minor,
/// patch, and as one number major·10000 + minor·100 + patch. The shared library's SONAME carries major.minor
/// (`libspherechain_c.so.0.1`): a library of another major.minor may not match this header.
#define SC_VERSION_MAJOR 0
#define SC_VERSION_MINOR 1
#define SC_VERSION_PATCH 0
#define SC_VERSION (SC_VERSION_MAJOR * 10000 + SC_VERSION_MINOR * 100 + SC_VERSION_PATCH)

/// The Asset.schema_version values this SDK loads (docs/format.md): older assets give
/// #SC_ERROR_VERSION_TOO_OLD (re-bake), newer ones #SC_ERROR_VERSION_TOO_NEW.
#define SC_SCHEMA_VERSION_OLDEST 1
#define SC_SCHEMA_VERSION_NEWEST 4

/// `SC_VERSION` of the library actually loaded, for a binding that loads `libspherechain_c` at run time and
/// was written against some header: compare `sc_version() / 100` with `SC_VERSION / 100` (major and minor).
/// Never fails. Thread-safe, O(1).
SC_API uint32_t sc_version(void);

/* ---- model: one asset ---------------------------------------------------------------------------------- */

/// What every character of one asset shares (the runtime's Model, plus its NarrowPhaseModel when created
/// with #SC_MODEL_NARROW_PHASE): opaque, immutable after sc_model_create(), thread-safe to share.
typedef struct sc_model sc_model;
/// One character's state for one model: its current spheres and per-frame scratch (the runtime's Workspace,
/// plus a NarrowPhaseWorkspace when its model has the narrow phase). Opaque; one call at a time.
typedef struct sc_workspace sc_workspace;

/// sc_model_create() flag: also build the narrow phase (sc_narrow_phase()), from the surrounding regions.
/// Costs time and memory at creation (with the crease rule: MakeHuman, 26,756 triangles, ~0.3 s and a few MB;
/// CesiumMan, 4,672 triangles, ~10 ms); needs an asset with `triangles` and `weld_ids` (else
/// #SC_ERROR_MISSING_FIELD).
#define SC_MODEL_NARROW_PHASE 0x1u
/// sc_model_create() flag (with #SC_MODEL_NARROW_PHASE): build the narrow phase on the reach regions (a
/// triangle stands behind every sphere that reaches it at bind, not only its owner), for a narrow phase
/// restricted to the broad phase's pairs (sc_narrow_phase_options::sphere_pairs). Unrestricted it finds the
/// same contacts at more cost. An asset without reach regions falls back to the surrounding regions.
#define SC_MODEL_NARROW_PHASE_REACH 0x2u

/// Loads a .sphc asset and builds its model: verifies the bytes (identifier "SPHC", schema version, the
/// FlatBuffers verifier, every count and index: runtime LoadAsset — untrusted bytes never crash), then
/// builds the runtime Model and, with #SC_MODEL_NARROW_PHASE, the narrow phase's model.
///
/// @param bytes  the whole .sphc file. [Limit: 8-byte aligned (malloc'ed memory is)] Borrowed, not copied:
///               the caller keeps them alive and unmodified until sc_model_destroy() (sc_sphere_triangles(),
///               sc_bind_positions(), sc_region_name() return pointers into them).
/// @param size   [bytes] [Limit: 8 .. 2^30]
/// @param flags  0, or #SC_MODEL_NARROW_PHASE, optionally | #SC_MODEL_NARROW_PHASE_REACH.
/// @param out    receives the model; set to NULL on every failure.
/// @return #SC_OK; #SC_ERROR_NULL_ARGUMENT (bytes or out null); #SC_ERROR_INVALID_JOB (unknown flag bits,
///         or #SC_MODEL_NARROW_PHASE_REACH without #SC_MODEL_NARROW_PHASE); the asset's own errors:
///         #SC_ERROR_ALIGNMENT, #SC_ERROR_ASSET_TOO_SMALL, #SC_ERROR_ASSET_TOO_LARGE, #SC_ERROR_IDENTIFIER,
///         #SC_ERROR_VERSION_TOO_OLD, #SC_ERROR_VERSION_TOO_NEW, #SC_ERROR_CORRUPT, and #SC_ERROR_MISSING_FIELD ..
///         #SC_ERROR_REGIONS (semantic checks; with #SC_MODEL_NARROW_PHASE also #SC_ERROR_MISSING_FIELD for an
///         asset baked without `triangles` / `weld_ids`, #SC_ERROR_BIND_POSE_TANGLED for a bind pose that
///         passes through itself beyond the narrow phase's budget, and #SC_ERROR_CREASE_TOO_WIDE for a crease
///         that reaches too much of the bind surface); #SC_ERROR_OUT_OF_MEMORY.
/// Cost: O(size) verification + O(\#S²) model build (+ the narrow phase's, see #SC_MODEL_NARROW_PHASE);
/// allocates (the only allocating call besides sc_workspace_create()). Thread-safe (no shared state).
SC_API sc_status sc_model_create(const void* bytes, size_t size, uint32_t flags, sc_model** out);

/// Frees a model. [opt] `model`: NULL does nothing. Workspaces do not point into their model: they may be
/// destroyed before or after it, but no call may use a destroyed model.
SC_API void sc_model_destroy(sc_model* model);

/// Counts and parameters of a model's asset (sc_model_get_info()). Plain data; zero-initialise or fill.
typedef struct sc_model_info {
  uint32_t sphere_count;    ///< \#S, 1..65535
  uint32_t vertex_count;    ///< \#V: the vertex buffer length refit and narrow phase take (Asset.fingerprint)
  uint32_t triangle_count;  ///< \#T: the source mesh's triangles (sc_contact indices are below it)
  uint32_t chain_count;     ///< chains (Table 1 of the paper: 6 for a body), 0..32
  uint32_t joint_count;     ///< \#J the joint refit takes (Asset.joint_count); 0 when the asset has no joint
                            ///< weights (unrigged bake, schema v1/v2): sc_refit_joints() is refused then
  uint32_t region_count;    ///< regions of the body (sc_region_name()): 10 for a biped's extended layout (the
                            ///< default; R9 torso), 5 for the paper's, a creature's limbs and trunk
  uint32_t schema_version;  ///< Asset.schema_version (1..4)
  uint32_t has_narrow_phase;  ///< 1 when created with #SC_MODEL_NARROW_PHASE, else 0
  uint32_t has_crease;      ///< 1 when the asset carries the crease rule (Asset.bind_positions, crease):
                            ///< #SC_EXCLUSIONS_CREASE works (with the narrow phase), sc_bind_positions() too
  float contact_margin;     ///< [Units: source] the asset's contact margin: sc_detect()'s default
  float crease;             ///< [Units: source] the asset's crease (fold distance), 0 without the rule
} sc_model_info;

/// Fills `*info` with the model's counts. Returns #SC_OK, or #SC_ERROR_NULL_ARGUMENT (nothing written).
/// O(1), thread-safe.
SC_API sc_status sc_model_get_info(const sc_model* model, sc_model_info* info);

/// The surrounding region of sphere `sphere` (paper §5.1: the triangles whose nearest sphere it is; what a
/// narrow phase tests when the sphere collides): `*count` source triangle indices (< \#T), ascending.
/// Zero-copy: `*triangles` points into the asset bytes (lifetime: those bytes); NULL when `*count` is 0.
/// Returns #SC_OK; #SC_ERROR_NULL_ARGUMENT; #SC_ERROR_INDEX_OUT_OF_RANGE (sphere >= \#S). On failure
/// `*triangles` = NULL and `*count` = 0 where given. O(1), thread-safe.
SC_API sc_status sc_sphere_triangles(const sc_model* model, uint32_t sphere, const uint32_t** triangles,
                                     uint32_t* count);

/// The asset's bind pose vertex buffer (Asset.bind_positions): `*vertex_count` (= \#V) vertices of 3 floats
/// (x, y, z), packed (stride 12) [Units: source; Space: model, bind pose]. Zero-copy, 4-byte aligned, into the
/// asset bytes (lifetime: those bytes). Present in assets baked with the crease rule
/// (sc_model_info::has_crease). Returns #SC_OK; #SC_ERROR_NULL_ARGUMENT; #SC_ERROR_MISSING_FIELD (absent:
/// `*positions` = NULL, `*vertex_count` = 0). O(1), thread-safe.
SC_API sc_status sc_bind_positions(const sc_model* model, const float** positions, uint32_t* vertex_count);

/// The region of sphere `sphere` (Asset.sphere_regions): an index < sc_model_info::region_count, whose
/// name sc_region_name() gives. Returns #SC_OK; #SC_ERROR_NULL_ARGUMENT; #SC_ERROR_INDEX_OUT_OF_RANGE
/// (sphere >= \#S); #SC_ERROR_MISSING_FIELD (the asset records no regions). `*region` is 0xFFFFFFFF on
/// failure (when given). O(1), thread-safe.
SC_API sc_status sc_sphere_region(const sc_model* model, uint32_t sphere, uint32_t* region);

/// Name of region `region`: the extended layout's "left_arm", "right_arm", "left_leg", "right_leg", "head",
/// "left_hand", "right_hand", "left_foot", "right_foot", "torso" (a body without some of those parts keeps
/// them in its limbs and has fewer), the paper's five ("left_arm" … "torso"), or a creature's ("HindLeg_L",
/// "Tail", "trunk"); the last region is the trunk. "" for a NULL model or region >= sc_model_info::region_count.
/// Never null. Lifetime: the asset bytes (or static). O(1), thread-safe.
SC_API const char* sc_region_name(const sc_model* model, uint32_t region);

/* ---- workspace: one character -------------------------------------------------------------------------- */

/// Creates a workspace (one character) for `model`, its spheres at the bind pose. With a narrow-phase
/// model it also holds the narrow phase's scratch (several MB for MakeHuman; docs/runtime.md gives the sizes).
/// @param model  the model the workspace will be used with (only read during the call).
/// @param out    receives the workspace; set to NULL on failure.
/// @return #SC_OK; #SC_ERROR_NULL_ARGUMENT; #SC_ERROR_OUT_OF_MEMORY.
/// Cost: O(\#S + broad-phase lanes + (narrow phase) \#T); allocates. Thread-safe (the model is only read).
SC_API sc_status sc_workspace_create(const sc_model* model, sc_workspace** out);

/// Frees a workspace. [opt] `workspace`: NULL does nothing.
SC_API void sc_workspace_destroy(sc_workspace* workspace);

/// Copies the workspace's current spheres (after the last refit; the bind pose after creation) into
/// `xyzr`: sphere i at xyzr[4i .. 4i+3] = centre x, y, z and radius [Units, space: those of the positions
/// last refitted]. Writes min(capacity, \#S) spheres; `*count` = \#S.
/// @param workspace  the character.
/// @param xyzr       [opt when capacity == 0] capacity × 4 floats.
/// @param capacity   spheres `xyzr` holds; \#S never truncates.
/// @param count      out: \#S.
/// @return #SC_OK; #SC_OK_TRUNCATED (capacity < \#S); #SC_ERROR_NULL_ARGUMENT (workspace or count null, or
///         xyzr null with capacity > 0).
/// O(\#S), no allocation.
SC_API sc_status sc_workspace_spheres(const sc_workspace* workspace, float* xyzr, uint32_t capacity,
                                      uint32_t* count);

/* ---- per frame: refit ------------------------------------------------------------------------------------ */

/// Refits the character's spheres to its deformed vertices (paper §5.1, the pivot-frame variant: every
/// sphere follows its four pivot triangles, exact under rigid motion): runtime RefitJob, kPivotFrame.
/// @param model         the asset's model.
/// @param workspace     the character, made for `model`; its spheres are overwritten.
/// @param positions     the deformed vertex buffer, the asset's vertex order (the source file's, as baked):
///                      vertex i is 3 floats (x, y, z) at `(const char*)positions + i * stride_bytes`
///                      [Units: source; Space: model, or any rigid motion of it] [Limit: 4-byte aligned].
///                      Borrowed for the call. Not checked for NaN: a non-finite vertex gives non-finite
///                      spheres, which never overlap.
/// @param vertex_count  [Limit: == sc_model_info::vertex_count]
/// @param stride_bytes  bytes from one vertex to the next [Limit: >= 12, multiple of 4, < 2^32] (12 = packed).
/// @return #SC_OK; #SC_ERROR_NULL_ARGUMENT; #SC_ERROR_WORKSPACE_MODEL; #SC_ERROR_ALIGNMENT;
///         #SC_ERROR_STRIDE; #SC_ERROR_VERTEX_COUNT. On failure the spheres are untouched.
/// Cost: O(\#S): 12 vertex reads and ~120 flops per sphere (SIMD); no allocation.
SC_API sc_status sc_refit_vertices(const sc_model* model, sc_workspace* workspace, const float* positions,
                                   uint32_t vertex_count, size_t stride_bytes);

/// Refits the character's spheres from the skin's joint matrices, for games that skin on the GPU (runtime
/// JointRefitJob): each sphere centre is skinned like a vertex from its four joint weights (Asset, schema
/// v3); radii stay the bind radii.
/// @param model           the asset's model (sc_model_info::joint_count > 0).
/// @param workspace       the character, made for `model`; its spheres are overwritten.
/// @param joint_matrices  joint_count × 12 floats, packed: per joint the 3×4 row-major affine skinning matrix
///                        (rows r0, r1, r2 of M = joint's model-space transform · inverse bind matrix, each
///                        [m_r0 m_r1 m_r2 t_r]) in the skin's joint order. A column-major 4×4 (glTF, glm)
///                        `m` gives out[4r + c] = m[4c + r] for r < 3. [Units: source] [Limit: 4-byte aligned]
/// @param joint_count     \#J [Limit: == sc_model_info::joint_count]
/// @return #SC_OK; #SC_ERROR_NULL_ARGUMENT; #SC_ERROR_WORKSPACE_MODEL; #SC_ERROR_MISSING_FIELD (the asset
///         has no joint weights: unrigged bake or schema v1/v2 — re-bake); #SC_ERROR_JOINT_COUNT;
///         #SC_ERROR_ALIGNMENT; #SC_ERROR_NON_FINITE_JOINTS (a matrix holds a NaN or an infinity). On failure
///         the spheres are untouched.
/// Cost: O(\#J + \#S): ≤ 48 multiply-adds per sphere; no allocation.
SC_API sc_status sc_refit_joints(const sc_model* model, sc_workspace* workspace, const float* joint_matrices,
                                 uint32_t joint_count);

/* ---- per frame: broad phase ------------------------------------------------------------------------------ */

/// Which sphere pairs sc_detect() tests (paper §5.2). Both skip the asset's excluded (adjacent) pairs.
typedef enum sc_detect_method {
  SC_DETECT_M1 = 0,  ///< pairs inside each chain (with chains)
  SC_DETECT_M2 = 1,  ///< every pair of spheres (without chains)
  SC_DETECT_MAX_ENUM = 0x7FFFFFFF  ///< not a method: keeps the type 32 bits wide (any other value is refused)
} sc_detect_method;

/// One overlapping sphere pair. 12 bytes, the layout of the runtime's Collision.
typedef struct sc_pair {
  uint16_t a;       ///< sphere index, a < b
  uint16_t b;       ///< sphere index (< \#S)
  float depth;      ///< rA + rB − ‖cA − cB‖ [Units: source]: > 0 overlapping; in (−2·margin, 0] apart but
                    ///< within the contact margin
  uint32_t chains;  ///< bit c set ⇔ chain c holds both spheres (M1: never 0; M2: may be 0)
} sc_pair;

/// Most pairs sc_detect() can report with `method` for this model: a buffer of that many ::sc_pair is never
/// truncated. M2: \#S(\#S−1)/2; M1: min(Σ_chains n(n−1)/2, \#S(\#S−1)/2). 0 for a NULL model or an
/// unknown method. O(\#chains), thread-safe. Its byte size (× sizeof(::sc_pair), 12) fits a 64-bit size_t
/// for any asset; on a 32-bit target it overflows past about 26,700 spheres: check before allocating there.
SC_API uint32_t sc_detect_bound(const sc_model* model, sc_detect_method method);

/// Broad phase: the overlapping, non-excluded sphere pairs of the character's current spheres (after a
/// refit, or the bind pose): runtime DetectJob. A pair is reported when ‖cA − cB‖ < rA + rB + 2·margin
/// (pairs of two spheres of one region use the asset's fold margin instead, when it has one).
/// Order (deterministic): M1 by chain, then rows of the chain; M2 lexicographic (a, b).
/// @param model      the asset's model.
/// @param workspace  the character, made for `model` (its spheres read, its scratch written).
/// @param method     #SC_DETECT_M1 or #SC_DETECT_M2.
/// @param margin     contact margin [Units: source] (radii grow by it); < 0: the asset's
///                   (sc_model_info::contact_margin). [Limit: not NaN, not +inf]
/// @param pairs      [opt when capacity == 0] caller buffer of `capacity` records.
/// @param capacity   records `pairs` holds; sc_detect_bound() never truncates.
/// @param count      out: the number of overlapping pairs found — also when more than `capacity` (then
///                   only the first `capacity`, in the order above, were written); 0 on failure.
/// @return #SC_OK; #SC_OK_TRUNCATED (`*count` > capacity); #SC_ERROR_NULL_ARGUMENT (model, workspace or
///         count null, or pairs null with capacity > 0); #SC_ERROR_WORKSPACE_MODEL; #SC_ERROR_INVALID_JOB
///         (unknown method, margin NaN or +inf). Nothing written on failure.
/// Cost: O(\#S) plus the kept block pairs' sphere tests (broad phase of blocks of 8 spheres, SIMD); no
/// allocation.
SC_API sc_status sc_detect(const sc_model* model, sc_workspace* workspace, sc_detect_method method, float margin,
                           sc_pair* pairs, uint32_t capacity, uint32_t* count);

/// The proxy's folds (runtime FoldPairs): the sphere pairs sc_detect() never reports (the asset's excluded
/// neighbours) whose centres are now closer than at bind pose by more than `closing` — a bent joint, where
/// the skin on either side may meet. With sc_detect()'s pairs they are the `sphere_pairs` of a
/// #SC_EXCLUSIONS_CREASE narrow phase behind the proxy (`spherechain play --narrow-behind` uses sc_detect's
/// margin 1.5 × the contact margin and `closing` 2 × it).
/// @param model      the asset's model, created with #SC_MODEL_NARROW_PHASE on an asset with the crease rule.
/// @param workspace  the character, made for `model` (its current spheres read).
/// @param closing    [Units: source] [Limit: finite, >= 0].
/// @param pairs      [opt when capacity == 0] caller buffer of `capacity` records (a < b, ascending; depth as
///                   sc_detect's; chains 0).
/// @param capacity   records `pairs` holds; the asset's excluded pairs never truncate.
/// @param count      out: the folds found — also when more than `capacity`; 0 on failure.
/// @return #SC_OK; #SC_OK_TRUNCATED; #SC_ERROR_NULL_ARGUMENT; #SC_ERROR_WORKSPACE_MODEL;
///         #SC_ERROR_INVALID_JOB (no narrow phase or no crease rule, closing NaN, infinite or < 0).
/// Cost: one distance per excluded pair; no allocation.
SC_API sc_status sc_fold_pairs(const sc_model* model, const sc_workspace* workspace, float closing, sc_pair* pairs,
                               uint32_t capacity, uint32_t* count);

/* ---- per frame: narrow phase ----------------------------------------------------------------------------- */

/// Which triangle pairs sc_narrow_phase() reports (runtime Exclusions).
typedef enum sc_exclusions {
  /// Intersecting triangles of two spheres' surrounding regions, minus the asset's excluded sphere pairs
  /// (what the broad phase skips too). The default.
  SC_EXCLUSIONS_ASSET = 0,
  /// Intersecting triangles of any two different spheres' regions (shows skinning artefacts at joints).
  SC_EXCLUSIONS_NONE = 1,
  /// The skin's own definition: every pair of intersecting triangles that share no welded corner and are
  /// not within the crease of each other on the welded bind surface (nor within two triangle rings),
  /// whichever spheres own them. Needs an asset with the crease rule (else #SC_ERROR_MISSING_FIELD).
  /// sphere_pairs NULL: the exact answer; given: only the skin behind them (runtime narrow_phase.h,
  /// Exclusions::kCrease: the pairs of patches behind a listed pair's two spheres, and the bind pose's own
  /// contacts). Penetration depths on request.
  SC_EXCLUSIONS_CREASE = 2,
  SC_EXCLUSIONS_MAX_ENUM = 0x7FFFFFFF  ///< not a value: keeps the type 32 bits wide (any other value is refused)
} sc_exclusions;

/// Options of sc_narrow_phase(). Zero-initialised (`sc_narrow_phase_options o = {0};`) = the defaults, as
/// is passing NULL.
typedef struct sc_narrow_phase_options {
  sc_exclusions exclusions;   ///< which contacts count (default #SC_EXCLUSIONS_ASSET)
  /// #SC_EXCLUSIONS_CREASE only: the fold distance [Units: source]; 0 = the asset's
  /// (sc_model_info::crease). [Limit: 0 or >= the asset's crease, finite; 0 with other exclusions, else
  /// #SC_ERROR_INVALID_JOB]
  float crease;
  /// [opt] restrict the search to these sphere pairs (e.g. sc_detect()'s output: only the contacts behind
  /// the broad phase's pairs); NULL = every sphere pair (the exact answer). With #SC_EXCLUSIONS_CREASE, the
  /// skin behind them (see #SC_EXCLUSIONS_CREASE; add sc_fold_pairs()' folds).
  /// Only a, b are read [Limit: a < b < \#S].
  const sc_pair* sphere_pairs;
  uint32_t sphere_pair_count;  ///< records in sphere_pairs
  /// [opt] #SC_EXCLUSIONS_CREASE only: the skinning matrices that deformed `positions` (joint_count × 12
  /// floats, sc_refit_joints()'s layout), for the joint-matrix cull: neighbouring skin that moved nearly
  /// rigidly is skipped, the same contacts found (runtime NarrowPhaseJob::joint_matrices, which states the
  /// bound). Needs an asset baked with the skin weights (`bake --skin-weights`; else
  /// #SC_ERROR_MISSING_FIELD). [Precondition: the positions are the asset's bind pose skinned by linear blend
  /// with these matrices and the asset's weights; another deformation could lose contacts.] NULL: none.
  const float* joint_matrices;
  uint32_t joint_count;  ///< matrices in joint_matrices [Limit: == the asset's \#J]
} sc_narrow_phase_options;

/// One contact: two intersecting triangles of the deformed mesh. 12 bytes, the runtime's TriangleContact.
typedef struct sc_contact {
  uint32_t triangle_a;  ///< source triangle index (< \#T), owned by sphere_a
  uint32_t triangle_b;  ///< source triangle index (< \#T), owned by sphere_b
  uint16_t sphere_a;    ///< owning sphere; sphere_a < sphere_b (#SC_EXCLUSIONS_CREASE: <=, and 0xFFFF for a
                        ///< triangle no sphere owns)
  uint16_t sphere_b;    ///< owning sphere
} sc_contact;

/// How far a contact's triangles pass through each other (#SC_EXCLUSIONS_CREASE). 16 bytes, the runtime's
/// ContactDepth: moving triangle_a by depth·direction (or triangle_b by −depth·direction) separates them
/// along a face normal (a local, separating-axis estimate).
typedef struct sc_contact_depth {
  float depth;         ///< [Units: source] >= 0
  float direction[3];  ///< unit vector [Space: the positions'], or (0, 0, 0) for a degenerate triangle
} sc_contact_depth;

/// Narrow phase: the exact self-contacts of the deformed mesh (runtime NarrowPhaseJob): triangle pairs that
/// share no welded corner and intersect (closed triangles, exact predicates), per `options->exclusions`.
/// Order (deterministic): by sphere pair, then as the sweep meets the triangles.
/// @param model         the asset's model, created with #SC_MODEL_NARROW_PHASE.
/// @param workspace     the character, made for `model` (its narrow-phase scratch written; its spheres are
///                      neither read nor written).
/// @param positions     the deformed vertex buffer, as sc_refit_vertices() takes it. Every vertex of a
///                      tested region must be finite.
/// @param vertex_count  [Limit: == sc_model_info::vertex_count]
/// @param stride_bytes  [Limit: >= 12, multiple of 4, < 2^32]
/// @param options       [opt] NULL = defaults (see ::sc_narrow_phase_options).
/// @param contacts      [opt when capacity == 0] caller buffer of `capacity` records.
/// @param depths        [opt] #SC_EXCLUSIONS_CREASE only (ignored otherwise): caller buffer of `capacity`
///                      records, depths[i] for contacts[i]; NULL: not computed.
/// @param capacity      records `contacts` (and `depths`) hold. The only bound is the job's budget (16 a
///                      triangle plus 4,096), far more than a frame finds: size it for the worst frame you
///                      expect, and grow it (outside the frame) when `*count` exceeds it.
/// @param count         out: the number of contacts found — also when more than `capacity` (then only the
///                      first `capacity` were written); 0 on failure.
/// @return #SC_OK; #SC_OK_TRUNCATED (`*count` > capacity); #SC_ERROR_NULL_ARGUMENT (model, workspace,
///         positions or count null; contacts null with capacity > 0; sphere_pairs null with a count > 0);
///         #SC_ERROR_WORKSPACE_MODEL; #SC_ERROR_INVALID_JOB (model created without #SC_MODEL_NARROW_PHASE,
///         unknown exclusions, #SC_EXCLUSIONS_CREASE with a crease below the asset's, negative or not finite; a
///         non-zero crease with other exclusions; joint_matrices with other exclusions); #SC_ERROR_MISSING_FIELD
///         (#SC_EXCLUSIONS_CREASE on an asset without the crease rule; joint_matrices on one without skin
///         weights); #SC_ERROR_JOINT_COUNT; #SC_ERROR_NON_FINITE_JOINTS (a matrix holds a NaN or an infinity);
///         #SC_ERROR_ALIGNMENT; #SC_ERROR_STRIDE; #SC_ERROR_VERTEX_COUNT; #SC_ERROR_INDEX_OUT_OF_RANGE
///         (a sphere pair with a >= b or b >= \#S); #SC_ERROR_NON_FINITE_POSITIONS (a tested vertex is NaN or
///         infinite); #SC_ERROR_FRAME_TANGLED (the frame's skin passes through itself
///         beyond the budget of the runtime's NarrowPhaseModel::kSweepTestsPerTriangle — positions that are no
///         pose of the character; it stops there: `*count` 0, contacts / depths hold unspecified records).
///         Otherwise nothing written to contacts / depths on failure.
/// Cost: O(\#V) region boxes, then only the triangles near other regions (box culls, sort and sweep);
/// #SC_EXCLUSIONS_CREASE on MakeHuman (26,756 triangles): ~0.4 ms a frame, one core; no allocation.
SC_API sc_status sc_narrow_phase(const sc_model* model, sc_workspace* workspace, const float* positions,
                                 uint32_t vertex_count, size_t stride_bytes, const sc_narrow_phase_options* options,
                                 sc_contact* contacts, sc_contact_depth* depths, uint32_t capacity, uint32_t* count);

#ifdef __cplusplus
}  // extern "C"
#endif

#endif  // SPHERECHAIN_SPHERECHAIN_H
