/* The C API (spherechain/spherechain.h) from a C99 program, compiled with -std=c99 -Wall -Wextra -Werror
 * -pedantic (tests/CMakeLists.txt). Two modes:
 *
 *   c_api_c99 golden V3.sphc V1.sphc   the golden assets of the repository (always present): every error path
 *                                      (NULL pointers, misaligned, truncated and corrupt bytes, flags, unknown
 *                                      methods, a workspace of another model, joint refit errors), the joint refit
 *                                      on identity and translation matrices, status strings.
 *   c_api_c99 real ASSET.sphc          a real bake with the crease rule (CesiumMan, fixture c_api_asset; MakeHuman):
 *                                      refit from its bind positions and from a deformed frame (an arm pushed
 *                                      into the body; any stride), M1, M2, truncation, the narrow phase (crease
 *                                      rule with depths, asset exclusions, restricted to the M2 pairs), strides,
 *                                      counts, NaN positions. Prints "SKIPPED: ..." when the asset is absent.
 *
 * tests/c_api/c_api_equivalence_test.cpp checks the same calls against the C++ runtime, record for record.
 * Exit 0 when every check passed, 1 otherwise (each failure printed with its line). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "spherechain/spherechain.h"

static int g_failures = 0;
static int g_checks = 0;

#define CHECK(cond)                                                            \
  do {                                                                         \
    ++g_checks;                                                                \
    if (!(cond)) {                                                             \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      ++g_failures;                                                            \
    }                                                                          \
  } while (0)

#define CHECK_STATUS(expr, expected)                                                                                  \
  do {                                                                                                                \
    const sc_status got_ = (expr);                                                                                    \
    const sc_status want_ = (expected);                                                                               \
    ++g_checks;                                                                                                       \
    if (got_ != want_) {                                                                                              \
      fprintf(stderr, "%s:%d: %s\n  returned %s\n  expected %s\n", __FILE__, __LINE__, #expr, sc_status_string(got_), \
              sc_status_string(want_));                                                                               \
      ++g_failures;                                                                                                   \
    }                                                                                                                 \
  } while (0)

/* The whole file in malloc'ed (so 8-byte aligned) memory; NULL when it cannot be read. */
static void* ReadFile(const char* path, size_t* size) {
  FILE* f = fopen(path, "rb");
  void* bytes = NULL;
  long n;
  if (!f) return NULL;
  if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0) {
    bytes = malloc((size_t)n);
    if (bytes && fread(bytes, 1, (size_t)n, f) != (size_t)n) {
      free(bytes);
      bytes = NULL;
    }
    *size = (size_t)n;
  }
  fclose(f);
  return bytes;
}

static int FileExists(const char* path) {
  FILE* f = fopen(path, "rb");
  if (f) fclose(f);
  return f != NULL;
}

/* ---- golden: error paths, joint refit --------------------------------------------------------------------- */

static void TestStatusStrings(void) {
  static const struct {
    sc_status status;
    const char* name;
  } all[] = {
      {SC_OK, "SC_OK"},
      {SC_OK_TRUNCATED, "SC_OK_TRUNCATED"},
      {SC_ERROR_NULL_ARGUMENT, "SC_ERROR_NULL_ARGUMENT"},
      {SC_ERROR_ALIGNMENT, "SC_ERROR_ALIGNMENT"},
      {SC_ERROR_INVALID_JOB, "SC_ERROR_INVALID_JOB"},
      {SC_ERROR_VERTEX_COUNT, "SC_ERROR_VERTEX_COUNT"},
      {SC_ERROR_STRIDE, "SC_ERROR_STRIDE"},
      {SC_ERROR_OUT_OF_MEMORY, "SC_ERROR_OUT_OF_MEMORY"},
      {SC_ERROR_NON_FINITE_POSITIONS, "SC_ERROR_NON_FINITE_POSITIONS"},
      {SC_ERROR_JOINT_COUNT, "SC_ERROR_JOINT_COUNT"},
      {SC_ERROR_NON_FINITE_JOINTS, "SC_ERROR_NON_FINITE_JOINTS"},
      {SC_ERROR_WORKSPACE_MODEL, "SC_ERROR_WORKSPACE_MODEL"},
      {SC_ERROR_BUFFER_TOO_SMALL, "SC_ERROR_BUFFER_TOO_SMALL"},
      {SC_ERROR_FRAME_TANGLED, "SC_ERROR_FRAME_TANGLED"},
      {SC_ERROR_ASSET_TOO_SMALL, "SC_ERROR_ASSET_TOO_SMALL"},
      {SC_ERROR_ASSET_TOO_LARGE, "SC_ERROR_ASSET_TOO_LARGE"},
      {SC_ERROR_IDENTIFIER, "SC_ERROR_IDENTIFIER"},
      {SC_ERROR_VERSION_TOO_OLD, "SC_ERROR_VERSION_TOO_OLD"},
      {SC_ERROR_VERSION_TOO_NEW, "SC_ERROR_VERSION_TOO_NEW"},
      {SC_ERROR_CORRUPT, "SC_ERROR_CORRUPT"},
      {SC_ERROR_MISSING_FIELD, "SC_ERROR_MISSING_FIELD"},
      {SC_ERROR_NO_SPHERES, "SC_ERROR_NO_SPHERES"},
      {SC_ERROR_TOO_MANY_SPHERES, "SC_ERROR_TOO_MANY_SPHERES"},
      {SC_ERROR_TOO_MANY_CHAINS, "SC_ERROR_TOO_MANY_CHAINS"},
      {SC_ERROR_COUNT_MISMATCH, "SC_ERROR_COUNT_MISMATCH"},
      {SC_ERROR_INDEX_OUT_OF_RANGE, "SC_ERROR_INDEX_OUT_OF_RANGE"},
      {SC_ERROR_OFFSETS, "SC_ERROR_OFFSETS"},
      {SC_ERROR_NON_FINITE, "SC_ERROR_NON_FINITE"},
      {SC_ERROR_RADIUS, "SC_ERROR_RADIUS"},
      {SC_ERROR_PIVOT_FRAME, "SC_ERROR_PIVOT_FRAME"},
      {SC_ERROR_CHAIN_ORDER, "SC_ERROR_CHAIN_ORDER"},
      {SC_ERROR_EXCLUDED_PAIRS, "SC_ERROR_EXCLUDED_PAIRS"},
      {SC_ERROR_CONTACT_MARGIN, "SC_ERROR_CONTACT_MARGIN"},
      {SC_ERROR_SKIN_WEIGHTS, "SC_ERROR_SKIN_WEIGHTS"},
      {SC_ERROR_REGIONS, "SC_ERROR_REGIONS"},
      {SC_ERROR_BIND_POSE_TANGLED, "SC_ERROR_BIND_POSE_TANGLED"},
      {SC_ERROR_CREASE_TOO_WIDE, "SC_ERROR_CREASE_TOO_WIDE"},
  };
  size_t i;
  for (i = 0; i < sizeof(all) / sizeof(all[0]); ++i) {
    const char* text = sc_status_string(all[i].status);
    const size_t n = strlen(all[i].name);
    CHECK(text != NULL && strncmp(text, all[i].name, n) == 0 && (text[n] == '\0' || text[n] == ':'));
    CHECK(SC_SUCCEEDED(all[i].status) == (i < 2));
    CHECK(SC_FAILED(all[i].status) == (i >= 2));
  }
  CHECK(strcmp(sc_status_string(0x12345u), "unknown status") == 0);
  CHECK(strcmp(sc_status_string(0x80000000u), "unknown status") == 0);
}

static void TestLoadErrors(const unsigned char* bytes, size_t size) {
  sc_model* model = (sc_model*)(uintptr_t)1; /* must come back NULL on every failure */
  unsigned char* copy = (unsigned char*)malloc(size + 16);
  size_t n;
  CHECK(copy != NULL);
  if (!copy) return;

  CHECK_STATUS(sc_model_create(NULL, size, 0, &model), SC_ERROR_NULL_ARGUMENT);
  CHECK(model == NULL);
  CHECK_STATUS(sc_model_create(bytes, size, 0, NULL), SC_ERROR_NULL_ARGUMENT);
  /* Flags: unknown bits, reach without the narrow phase. */
  model = (sc_model*)(uintptr_t)1;
  CHECK_STATUS(sc_model_create(bytes, size, 0x4u, &model), SC_ERROR_INVALID_JOB);
  CHECK(model == NULL);
  CHECK_STATUS(sc_model_create(bytes, size, SC_MODEL_NARROW_PHASE_REACH, &model), SC_ERROR_INVALID_JOB);
  /* Misaligned bytes (malloc + 4). */
  memcpy(copy + 4, bytes, size);
  model = (sc_model*)(uintptr_t)1;
  CHECK_STATUS(sc_model_create(copy + 4, size, 0, &model), SC_ERROR_ALIGNMENT);
  CHECK(model == NULL);
  /* Too small, too large (checked before anything is read past the header). */
  CHECK_STATUS(sc_model_create(bytes, 0, 0, &model), SC_ERROR_ASSET_TOO_SMALL);
  CHECK_STATUS(sc_model_create(bytes, 7, 0, &model), SC_ERROR_ASSET_TOO_SMALL);
  CHECK_STATUS(sc_model_create(bytes, ((size_t)1 << 30) + 8, 0, &model), SC_ERROR_ASSET_TOO_LARGE);
  /* Not a .sphc: the identifier (bytes 4..7) changed. */
  memcpy(copy, bytes, size);
  copy[4] = 'X';
  CHECK_STATUS(sc_model_create(copy, size, 0, &model), SC_ERROR_IDENTIFIER);
  /* Truncated prefixes (each an error, none crashing: ASan watches the copy's end): the first 64 byte counts,
   * then ~200 spread over the file. Each prefix lives in its own allocation of exactly that size. */
  for (n = 8; n < size; n = n < 64 ? n + 1 : n + size / 200 + 1) {
    unsigned char* prefix = (unsigned char*)malloc(n);
    sc_status s;
    CHECK(prefix != NULL);
    if (!prefix) break;
    memcpy(prefix, bytes, n);
    model = (sc_model*)(uintptr_t)1;
    s = sc_model_create(prefix, n, 0, &model);
    CHECK(SC_FAILED(s) && model == NULL);
    if (SC_SUCCEEDED(s)) sc_model_destroy(model);
    free(prefix);
  }
  /* Bit flips in a copy: never a crash; a success must be a usable model. */
  for (n = 0; n < 256; ++n) {
    const size_t at = (n * 7919u) % size;
    sc_status s;
    memcpy(copy, bytes, size);
    copy[at] ^= (unsigned char)(1u << (n % 8));
    model = NULL;
    s = sc_model_create(copy, size, 0, &model);
    CHECK(SC_SUCCEEDED(s) == (model != NULL));
    if (model) {
      sc_model_info info;
      CHECK_STATUS(sc_model_get_info(model, &info), SC_OK);
      CHECK(info.sphere_count > 0);
      sc_model_destroy(model);
    }
  }
  free(copy);
}

static void TestGolden(const char* v3_path, const char* v1_path) {
  size_t size = 0, size_v1 = 0;
  unsigned char* bytes = (unsigned char*)ReadFile(v3_path, &size);
  unsigned char* bytes_v1 = (unsigned char*)ReadFile(v1_path, &size_v1);
  sc_model *model = NULL, *other = NULL, *model_v1 = NULL;
  sc_workspace *ws = NULL, *ws_other = NULL, *ws_v1 = NULL;
  sc_model_info info, info_v1;
  float *bind = NULL, *spheres = NULL, *matrices = NULL;
  sc_pair* pairs = NULL;
  uint32_t count = 0, bound_m1, bound_m2, s, j, region = 0;
  const uint32_t* triangles = NULL;
  const float* bind_positions = NULL;
  float dummy[12] = {0};
  CHECK(bytes != NULL && bytes_v1 != NULL);
  if (!bytes || !bytes_v1) return;

  TestStatusStrings();
  TestLoadErrors(bytes, size);

  CHECK_STATUS(sc_model_create(bytes, size, 0, &model), SC_OK);
  CHECK_STATUS(sc_model_create(bytes, size, 0, &other), SC_OK);
  CHECK_STATUS(sc_model_create(bytes_v1, size_v1, 0, &model_v1), SC_OK);
  if (!model || !other || !model_v1) return;
  CHECK_STATUS(sc_model_get_info(NULL, &info), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_model_get_info(model, NULL), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_model_get_info(model, &info), SC_OK);
  CHECK_STATUS(sc_model_get_info(model_v1, &info_v1), SC_OK);
  CHECK(info.schema_version == 3 && info_v1.schema_version == 1);
  CHECK(info_v1.schema_version == SC_SCHEMA_VERSION_OLDEST && info.schema_version <= SC_SCHEMA_VERSION_NEWEST);
  CHECK(sc_version() == SC_VERSION && SC_VERSION == SC_VERSION_MAJOR * 10000 + SC_VERSION_MINOR * 100 + SC_VERSION_PATCH);
  CHECK(info.sphere_count > 8 && info.chain_count == 6 && info.region_count == 5);
  CHECK(info.vertex_count > 0 && info.triangle_count > 0 && info.joint_count > 0 && info_v1.joint_count == 0);
  CHECK(info.has_narrow_phase == 0 && info.has_crease == 0 && info.crease == 0.0f && info.contact_margin >= 0.0f);

  /* Workspaces. */
  CHECK_STATUS(sc_workspace_create(NULL, &ws), SC_ERROR_NULL_ARGUMENT);
  CHECK(ws == NULL);
  CHECK_STATUS(sc_workspace_create(model, NULL), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_workspace_create(model, &ws), SC_OK);
  CHECK_STATUS(sc_workspace_create(other, &ws_other), SC_OK);
  CHECK_STATUS(sc_workspace_create(model_v1, &ws_v1), SC_OK);
  if (!ws || !ws_other || !ws_v1) return;

  /* The bind spheres, as a fresh workspace holds them; capacity 0 gives the count, truncated. */
  CHECK_STATUS(sc_workspace_spheres(ws, NULL, 0, &count), SC_OK_TRUNCATED);
  CHECK(count == info.sphere_count);
  CHECK_STATUS(sc_workspace_spheres(NULL, NULL, 0, &count), SC_ERROR_NULL_ARGUMENT);
  CHECK(count == 0);
  CHECK_STATUS(sc_workspace_spheres(ws, NULL, 3, &count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_workspace_spheres(ws, dummy, 3, NULL), SC_ERROR_NULL_ARGUMENT);
  bind = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
  spheres = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
  matrices = (float*)malloc(sizeof(float) * 12 * info.joint_count);
  if (!bind || !spheres || !matrices) return;
  CHECK_STATUS(sc_workspace_spheres(ws, dummy, 2, &count), SC_OK_TRUNCATED); /* writes 2 spheres: 8 floats */
  CHECK(count == info.sphere_count);
  CHECK_STATUS(sc_workspace_spheres(ws, bind, info.sphere_count, &count), SC_OK);
  CHECK(memcmp(dummy, bind, sizeof(float) * 8) == 0 && dummy[8] == 0.0f);
  for (s = 0; s < info.sphere_count; ++s) CHECK(bind[4 * s + 3] > 0.0f);

  /* Joint refit: identity matrices give the bind spheres (weights sum to 1 within 1e-3, radii unchanged). */
  for (j = 0; j < info.joint_count; ++j) {
    float* m = matrices + 12 * j;
    memset(m, 0, sizeof(float) * 12);
    m[0] = m[5] = m[10] = 1.0f;
  }
  CHECK_STATUS(sc_refit_joints(model, ws, matrices, info.joint_count), SC_OK);
  CHECK_STATUS(sc_workspace_spheres(ws, spheres, info.sphere_count, &count), SC_OK);
  for (s = 0; s < info.sphere_count; ++s) {
    int k;
    for (k = 0; k < 3; ++k)
      CHECK(fabsf(spheres[4 * s + k] - bind[4 * s + k]) <= 2e-3f * (1.0f + fabsf(bind[4 * s + k])));
    CHECK(spheres[4 * s + 3] == bind[4 * s + 3]);
  }
  /* A translation by t moves every centre by t. */
  for (j = 0; j < info.joint_count; ++j) {
    matrices[12 * j + 3] = 0.5f;
    matrices[12 * j + 7] = -1.0f;
    matrices[12 * j + 11] = 2.0f;
  }
  CHECK_STATUS(sc_refit_joints(model, ws, matrices, info.joint_count), SC_OK);
  CHECK_STATUS(sc_workspace_spheres(ws, spheres, info.sphere_count, &count), SC_OK);
  for (s = 0; s < info.sphere_count; ++s) {
    const float t[3] = {0.5f, -1.0f, 2.0f};
    int k;
    for (k = 0; k < 3; ++k)
      CHECK(fabsf(spheres[4 * s + k] - bind[4 * s + k] - t[k]) <= 2e-3f * (4.0f + fabsf(bind[4 * s + k])));
  }
  /* Joint refit errors: nothing written (the spheres stay the translated ones). */
  CHECK_STATUS(sc_refit_joints(NULL, ws, matrices, info.joint_count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_refit_joints(model, NULL, matrices, info.joint_count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_refit_joints(model, ws, NULL, info.joint_count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_refit_joints(model, ws, matrices, info.joint_count - 1), SC_ERROR_JOINT_COUNT);
  CHECK_STATUS(sc_refit_joints(model, ws, (const float*)((const char*)matrices + 2), info.joint_count),
               SC_ERROR_ALIGNMENT);
  CHECK_STATUS(sc_refit_joints(model, ws_other, matrices, info.joint_count), SC_ERROR_WORKSPACE_MODEL);
  CHECK_STATUS(sc_refit_joints(model_v1, ws_v1, matrices, info.joint_count), SC_ERROR_MISSING_FIELD);
  for (j = 0; j < info.joint_count; ++j) matrices[12 * j + 4] = (float)NAN;
  CHECK_STATUS(sc_refit_joints(model, ws, matrices, info.joint_count), SC_ERROR_NON_FINITE_JOINTS);
  {
    float* after = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
    if (after) {
      CHECK_STATUS(sc_workspace_spheres(ws, after, info.sphere_count, &count), SC_OK);
      CHECK(memcmp(after, spheres, sizeof(float) * 4 * info.sphere_count) == 0);
      free(after);
    }
  }

  /* Vertex refit errors (the golden assets carry no bind positions: a zero buffer stands in; every call below
   * is refused before reading it). */
  CHECK_STATUS(sc_bind_positions(model, &bind_positions, &count), SC_ERROR_MISSING_FIELD);
  CHECK(bind_positions == NULL && count == 0);
  CHECK_STATUS(sc_bind_positions(model, NULL, &count), SC_ERROR_NULL_ARGUMENT);
  {
    float* zeros = (float*)calloc((size_t)info.vertex_count * 3 + 4, sizeof(float));
    if (zeros) {
      CHECK_STATUS(sc_refit_vertices(NULL, ws, zeros, info.vertex_count, 12), SC_ERROR_NULL_ARGUMENT);
      CHECK_STATUS(sc_refit_vertices(model, NULL, zeros, info.vertex_count, 12), SC_ERROR_NULL_ARGUMENT);
      CHECK_STATUS(sc_refit_vertices(model, ws, NULL, info.vertex_count, 12), SC_ERROR_NULL_ARGUMENT);
      CHECK_STATUS(sc_refit_vertices(model, ws_other, zeros, info.vertex_count, 12), SC_ERROR_WORKSPACE_MODEL);
      CHECK_STATUS(sc_refit_vertices(model, ws, zeros, info.vertex_count - 1, 12), SC_ERROR_VERTEX_COUNT);
      CHECK_STATUS(sc_refit_vertices(model, ws, zeros, info.vertex_count, 8), SC_ERROR_STRIDE);
      CHECK_STATUS(sc_refit_vertices(model, ws, zeros, info.vertex_count, 14), SC_ERROR_STRIDE);
#if SIZE_MAX > UINT32_MAX
      CHECK_STATUS(sc_refit_vertices(model, ws, zeros, info.vertex_count, (size_t)UINT32_MAX + 5), SC_ERROR_STRIDE);
#endif
      CHECK_STATUS(sc_refit_vertices(model, ws, (const float*)((const char*)zeros + 1), info.vertex_count, 12),
                   SC_ERROR_ALIGNMENT);
      /* The narrow phase on a model created without it. */
      CHECK_STATUS(sc_narrow_phase(model, ws, zeros, info.vertex_count, 12, NULL, NULL, NULL, 0, &count),
                   SC_ERROR_INVALID_JOB);
      free(zeros);
    }
  }

  /* Broad phase on the bind pose: bounds, errors, the count query, truncation. */
  bound_m1 = sc_detect_bound(model, SC_DETECT_M1);
  bound_m2 = sc_detect_bound(model, SC_DETECT_M2);
  CHECK(bound_m2 == info.sphere_count * (info.sphere_count - 1) / 2 && bound_m1 > 0 && bound_m1 <= bound_m2);
  CHECK(sc_detect_bound(NULL, SC_DETECT_M1) == 0 && sc_detect_bound(model, (sc_detect_method)7) == 0);
  pairs = (sc_pair*)malloc(sizeof(sc_pair) * (bound_m2 + 1));
  if (!pairs) return;
  CHECK_STATUS(sc_refit_joints(model, ws, matrices, info.joint_count), SC_ERROR_NON_FINITE_JOINTS);
  count = 99;
  CHECK_STATUS(sc_detect(NULL, ws, SC_DETECT_M2, -1.0f, pairs, bound_m2, &count), SC_ERROR_NULL_ARGUMENT);
  CHECK(count == 0);
  CHECK_STATUS(sc_detect(model, NULL, SC_DETECT_M2, -1.0f, pairs, bound_m2, &count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, -1.0f, pairs, bound_m2, NULL), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, -1.0f, NULL, 4, &count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_detect(model, ws_other, SC_DETECT_M2, -1.0f, pairs, bound_m2, &count), SC_ERROR_WORKSPACE_MODEL);
  CHECK_STATUS(sc_detect(model, ws, (sc_detect_method)7, -1.0f, pairs, bound_m2, &count), SC_ERROR_INVALID_JOB);
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, (float)NAN, pairs, bound_m2, &count), SC_ERROR_INVALID_JOB);
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, (float)INFINITY, pairs, bound_m2, &count), SC_ERROR_INVALID_JOB);
  /* A margin of a tenth of the largest radius: the bind pose's neighbours overlap. */
  {
    float largest = 0.0f, margin;
    uint32_t full = 0, i;
    for (s = 0; s < info.sphere_count; ++s)
      if (bind[4 * s + 3] > largest) largest = bind[4 * s + 3];
    margin = 0.1f * largest;
    CHECK_STATUS(sc_refit_joints(model, ws, NULL, 0), SC_ERROR_NULL_ARGUMENT);
    CHECK_STATUS(sc_detect(model, ws_other, SC_DETECT_M2, margin, pairs, bound_m2, &full), SC_ERROR_WORKSPACE_MODEL);
    CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, margin, NULL, 0, &full), SC_OK_TRUNCATED); /* count query */
    CHECK(full > 1);
    CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, margin, pairs, bound_m2, &count), SC_OK);
    CHECK(count == full);
    for (i = 0; i < count; ++i) {
      CHECK(pairs[i].a < pairs[i].b && pairs[i].b < info.sphere_count);
      CHECK(pairs[i].depth > -2.0f * margin);
      if (i > 0) CHECK(pairs[i - 1].a < pairs[i].a || (pairs[i - 1].a == pairs[i].a && pairs[i - 1].b < pairs[i].b));
    }
    /* Truncated: the first capacity records (in order), the full count, nothing past capacity written. */
    if (full > 1) {
      sc_pair* part = (sc_pair*)malloc(sizeof(sc_pair) * full);
      if (part) {
        memset(part, 0xAB, sizeof(sc_pair) * full);
        CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, margin, part, full - 1, &count), SC_OK_TRUNCATED);
        CHECK(count == full);
        CHECK(memcmp(part, pairs, sizeof(sc_pair) * (full - 1)) == 0);
        CHECK(part[full - 1].a == 0xABABu && part[full - 1].b == 0xABABu);
        free(part);
      }
    }
  }

  /* Sphere queries. */
  CHECK_STATUS(sc_sphere_triangles(model, info.sphere_count, &triangles, &count), SC_ERROR_INDEX_OUT_OF_RANGE);
  CHECK(triangles == NULL && count == 0);
  CHECK_STATUS(sc_sphere_triangles(NULL, 0, &triangles, &count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_sphere_triangles(model, 0, NULL, &count), SC_ERROR_NULL_ARGUMENT);
  {
    uint32_t total = 0, i;
    for (s = 0; s < info.sphere_count; ++s) {
      CHECK_STATUS(sc_sphere_triangles(model, s, &triangles, &count), SC_OK);
      for (i = 0; i < count; ++i)
        CHECK(triangles[i] < info.triangle_count && (i == 0 || triangles[i - 1] < triangles[i]));
      total += count;
      CHECK_STATUS(sc_sphere_region(model, s, &region), SC_OK);
      CHECK(region < info.region_count && sc_region_name(model, region)[0] != '\0');
    }
    CHECK(total == info.triangle_count); /* every triangle in one surrounding region (CesiumMan: none unassigned) */
  }
  CHECK_STATUS(sc_sphere_region(model, info.sphere_count, &region), SC_ERROR_INDEX_OUT_OF_RANGE);
  CHECK(region == 0xFFFFFFFFu);
  CHECK_STATUS(sc_sphere_region(model, 0, NULL), SC_ERROR_NULL_ARGUMENT);
  CHECK(strcmp(sc_region_name(model, 0), "left_arm") == 0 && strcmp(sc_region_name(model, 4), "torso") == 0);
  CHECK(strcmp(sc_region_name(model, info.region_count), "") == 0 && strcmp(sc_region_name(NULL, 0), "") == 0);

  /* Destroying NULL does nothing; a workspace may outlive its model (it does not point into it). */
  sc_model_destroy(NULL);
  sc_workspace_destroy(NULL);
  sc_model_destroy(other);
  sc_workspace_destroy(ws_other);
  sc_workspace_destroy(ws_v1);
  sc_model_destroy(model_v1);
  sc_model_destroy(model);
  sc_workspace_destroy(ws);
  free(pairs);
  free(matrices);
  free(spheres);
  free(bind);
  free(bytes_v1);
  free(bytes);
}

/* ---- real: a baked character with the crease rule ------------------------------------------------------------ */

/* The deformed frame of the test (and of samples/hello_c): the vertices nearest a sphere of region `arm` (by
 * distance to the sphere's surface, at bind) moved 0.8 of the way from their centroid to the other vertices',
 * across the body (the two axes other than the longest extent, the height). */
static void PushArm(const sc_model* model, const float* bind_spheres, uint32_t sphere_count, const float* bind,
                    uint32_t vertex_count, const char* arm, float* out) {
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double sum[2][3] = {{0, 0, 0}, {0, 0, 0}};
  uint32_t n[2] = {0, 0}, v, s;
  unsigned char* in_arm = (unsigned char*)calloc(vertex_count, 1);
  int up = 0, k;
  if (!in_arm) return;
  for (v = 0; v < vertex_count; ++v)
    for (k = 0; k < 3; ++k) {
      if (bind[3 * v + k] < lo[k]) lo[k] = bind[3 * v + k];
      if (bind[3 * v + k] > hi[k]) hi[k] = bind[3 * v + k];
    }
  for (k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[up] - lo[up]) up = k;
  for (v = 0; v < vertex_count; ++v) {
    const float* p = bind + 3 * v;
    float best = INFINITY;
    uint32_t nearest = 0, region = 0;
    for (s = 0; s < sphere_count; ++s) {
      const float* c = bind_spheres + 4 * s;
      const float d =
          sqrtf((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) + (p[2] - c[2]) * (p[2] - c[2])) - c[3];
      if (d < best) best = d, nearest = s;
    }
    if (SC_SUCCEEDED(sc_sphere_region(model, nearest, &region)) && strcmp(sc_region_name(model, region), arm) == 0)
      in_arm[v] = 1;
    for (k = 0; k < 3; ++k) sum[in_arm[v]][k] += p[k];
    ++n[in_arm[v]];
  }
  memcpy(out, bind, sizeof(float) * 3 * vertex_count);
  if (n[0] > 0 && n[1] > 0)
    for (v = 0; v < vertex_count; ++v)
      if (in_arm[v])
        for (k = 0; k < 3; ++k)
          if (k != up) out[3 * v + k] -= (float)(0.8 * (sum[1][k] / n[1] - sum[0][k] / n[0]));
  free(in_arm);
}

static int SameContact(const sc_contact* x, const sc_contact* y) {
  return x->triangle_a == y->triangle_a && x->triangle_b == y->triangle_b && x->sphere_a == y->sphere_a &&
         x->sphere_b == y->sphere_b;
}

/* 1 when every one of some[0..n) is among all[0..n_all). */
static int AllAmong(const sc_contact* some, uint32_t n, const sc_contact* all, uint32_t n_all) {
  uint32_t i, j;
  for (i = 0; i < n; ++i) {
    int found = 0;
    for (j = 0; j < n_all && !found; ++j) found = SameContact(some + i, all + j);
    if (!found) return 0;
  }
  return 1;
}

static void TestReal(const char* path) {
  size_t size = 0;
  void* bytes = ReadFile(path, &size);
  sc_model *model = NULL, *plain = NULL;
  sc_workspace *ws = NULL, *ws_plain = NULL;
  sc_model_info info;
  const float* bind = NULL;
  float *bind_spheres = NULL, *spheres = NULL, *deformed = NULL, *strided = NULL, *moved = NULL;
  sc_pair *m1 = NULL, *m2 = NULL;
  sc_contact* contacts = NULL;
  sc_contact_depth* depths = NULL;
  uint32_t count = 0, n_bind = 0, n_m1 = 0, n_m2 = 0, vertex_count = 0, bound_m1, bound_m2, i, j, s, v;
  float height = 0.0f;
  CHECK(bytes != NULL);
  if (!bytes) return;
  CHECK_STATUS(sc_model_create(bytes, size, SC_MODEL_NARROW_PHASE, &model), SC_OK);
  CHECK_STATUS(sc_model_create(bytes, size, 0, &plain), SC_OK);
  if (!model || !plain) return;
  CHECK_STATUS(sc_model_get_info(model, &info), SC_OK);
  CHECK(info.has_narrow_phase == 1 && info.has_crease == 1 && info.crease > 0.0f);
  CHECK(info.chain_count > 0 && info.region_count >= 5);
  CHECK_STATUS(sc_bind_positions(model, &bind, &vertex_count), SC_OK);
  CHECK(bind != NULL && vertex_count == info.vertex_count);
  CHECK_STATUS(sc_workspace_create(model, &ws), SC_OK);
  CHECK_STATUS(sc_workspace_create(plain, &ws_plain), SC_OK);
  if (!bind || !ws || !ws_plain) return;
  for (i = 0; i < 3; ++i) { /* the body's height: its longest extent */
    float lo = INFINITY, hi = -INFINITY;
    for (v = 0; v < vertex_count; ++v) {
      if (bind[3 * v + i] < lo) lo = bind[3 * v + i];
      if (bind[3 * v + i] > hi) hi = bind[3 * v + i];
    }
    if (hi - lo > height) height = hi - lo;
  }
  bind_spheres = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
  spheres = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
  deformed = (float*)malloc(sizeof(float) * 3 * vertex_count);
  strided = (float*)malloc(sizeof(float) * 5 * vertex_count);
  moved = (float*)malloc(sizeof(float) * 3 * vertex_count);
  bound_m1 = sc_detect_bound(model, SC_DETECT_M1);
  bound_m2 = sc_detect_bound(model, SC_DETECT_M2);
  m1 = (sc_pair*)malloc(sizeof(sc_pair) * bound_m1);
  m2 = (sc_pair*)malloc(sizeof(sc_pair) * bound_m2);
  if (!bind_spheres || !spheres || !deformed || !strided || !moved || !m1 || !m2) return;
  CHECK_STATUS(sc_workspace_spheres(ws, bind_spheres, info.sphere_count, &count), SC_OK);

  /* Refit from the bind positions gives back the bind spheres (up to rounding). */
  CHECK_STATUS(sc_refit_vertices(model, ws, bind, vertex_count, 12), SC_OK);
  CHECK_STATUS(sc_workspace_spheres(ws, spheres, info.sphere_count, &count), SC_OK);
  for (i = 0; i < 4 * info.sphere_count; ++i) CHECK(fabsf(spheres[i] - bind_spheres[i]) <= 1e-4f * height);
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, -1.0f, m2, bound_m2, &n_bind), SC_OK);

  /* The deformed frame: the left arm pushed into the body. Packed and interleaved (stride 20: xyz + two other
   * floats) give the same spheres, bit for bit. */
  PushArm(model, bind_spheres, info.sphere_count, bind, vertex_count, "left_arm", deformed);
  for (v = 0; v < vertex_count; ++v) {
    memcpy(strided + 5 * v, deformed + 3 * v, sizeof(float) * 3);
    strided[5 * v + 3] = (float)NAN; /* never read */
    strided[5 * v + 4] = -1.0f;
  }
  CHECK_STATUS(sc_refit_vertices(model, ws, strided, vertex_count, 20), SC_OK);
  CHECK_STATUS(sc_workspace_spheres(ws, spheres, info.sphere_count, &count), SC_OK);
  CHECK_STATUS(sc_refit_vertices(model, ws, deformed, vertex_count, 12), SC_OK);
  {
    float* packed = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
    if (packed) {
      CHECK_STATUS(sc_workspace_spheres(ws, packed, info.sphere_count, &count), SC_OK);
      CHECK(memcmp(packed, spheres, sizeof(float) * 4 * info.sphere_count) == 0);
      free(packed);
    }
  }

  /* M2 and M1 on the deformed frame: more pairs than at bind, an arm–torso pair among them; M1's pairs are
   * among M2's (same spheres and chain bits, depths equal to rounding), M2 in lexicographic order. */
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, -1.0f, m2, bound_m2, &n_m2), SC_OK);
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M1, -1.0f, m1, bound_m1, &n_m1), SC_OK);
  CHECK(n_m2 > n_bind && n_m1 > 0 && n_m1 <= n_m2);
  {
    int arm_torso = 0;
    for (i = 0; i < n_m2; ++i) {
      uint32_t ra = 0, rb = 0;
      CHECK(m2[i].a < m2[i].b && m2[i].b < info.sphere_count && m2[i].depth > -2.0f * info.contact_margin);
      if (i > 0) CHECK(m2[i - 1].a < m2[i].a || (m2[i - 1].a == m2[i].a && m2[i - 1].b < m2[i].b));
      CHECK_STATUS(sc_sphere_region(model, m2[i].a, &ra), SC_OK);
      CHECK_STATUS(sc_sphere_region(model, m2[i].b, &rb), SC_OK);
      if ((strcmp(sc_region_name(model, ra), "left_arm") == 0 && strcmp(sc_region_name(model, rb), "torso") == 0) ||
          (strcmp(sc_region_name(model, rb), "left_arm") == 0 && strcmp(sc_region_name(model, ra), "torso") == 0))
        arm_torso = 1;
    }
    CHECK(arm_torso);
    for (i = 0; i < n_m1; ++i) {
      int found = 0;
      CHECK(m1[i].chains != 0 && m1[i].a < m1[i].b);
      for (j = 0; j < n_m2 && !found; ++j)
        found =
            m2[j].a == m1[i].a && m2[j].b == m1[i].b && m2[j].chains == m1[i].chains &&
            fabsf(m2[j].depth - m1[i].depth) <= 1e-6f * height; /* the two methods' depths differ in the last bits */
      CHECK(found);
    }
  }
  /* Truncated M1: the first records in M1's order, the full count. */
  if (n_m1 > 2) {
    sc_pair part[2];
    CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M1, -1.0f, part, 2, &count), SC_OK_TRUNCATED);
    CHECK(count == n_m1 && memcmp(part, m1, sizeof(part)) == 0);
  }
  /* A workspace of another model (same asset, another model) is refused; so is the plain model's narrow phase. */
  CHECK_STATUS(sc_detect(model, ws_plain, SC_DETECT_M1, -1.0f, m1, bound_m1, &count), SC_ERROR_WORKSPACE_MODEL);
  CHECK_STATUS(sc_narrow_phase(model, ws_plain, deformed, vertex_count, 12, NULL, NULL, NULL, 0, &count),
               SC_ERROR_WORKSPACE_MODEL);
  CHECK_STATUS(sc_narrow_phase(plain, ws_plain, deformed, vertex_count, 12, NULL, NULL, NULL, 0, &count),
               SC_ERROR_INVALID_JOB);

  /* A rigid motion (a translation) moves the spheres with it. */
  for (v = 0; v < 3 * vertex_count; ++v)
    moved[v] = deformed[v] + (v % 3 == 0 ? 0.25f : v % 3 == 1 ? -0.5f : 1.0f) * height;
  CHECK_STATUS(sc_refit_vertices(model, ws, moved, vertex_count, 12), SC_OK);
  {
    float* after = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
    if (after) {
      const float t[4] = {0.25f * height, -0.5f * height, 1.0f * height, 0.0f};
      CHECK_STATUS(sc_workspace_spheres(ws, after, info.sphere_count, &count), SC_OK);
      for (s = 0; s < info.sphere_count; ++s)
        for (i = 0; i < 4; ++i) CHECK(fabsf(after[4 * s + i] - spheres[4 * s + i] - t[i]) <= 1e-4f * height);
      free(after);
    }
  }

  /* Narrow phase, the skin's definition (crease rule) with depths: contacts on the deformed frame. The count
   * query (capacity 0) gives the size; a second call fills it. */
  {
    sc_narrow_phase_options crease = {SC_EXCLUSIONS_CREASE, 0.0f, NULL, 0, NULL, 0};
    uint32_t n_crease = 0, n_bind_crease = 0, n_wide = 0, n_asset = 0, n_restricted = 0, n_default = 0;
    CHECK_STATUS(sc_narrow_phase(model, ws, bind, vertex_count, 12, &crease, NULL, NULL, 0, &n_bind_crease),
                 n_bind_crease ? SC_OK_TRUNCATED : SC_OK);
    if (info.joint_count > 0) {
      /* The joint-matrix cull: the bind pose is the skin under identity matrices, the same count. An asset
       * baked without the skin weights refuses the matrices. */
      float* identity = (float*)calloc(12 * (size_t)info.joint_count, sizeof(float));
      uint32_t n_cull = 0, jj;
      sc_status cull;
      for (jj = 0; jj < info.joint_count; ++jj) identity[12 * jj] = identity[12 * jj + 5] = identity[12 * jj + 10] = 1.0f;
      crease.joint_matrices = identity;
      crease.joint_count = info.joint_count;
      cull = sc_narrow_phase(model, ws, bind, vertex_count, 12, &crease, NULL, NULL, 0, &n_cull);
      CHECK(cull == SC_ERROR_MISSING_FIELD || ((cull == SC_OK || cull == SC_OK_TRUNCATED) && n_cull == n_bind_crease));
      crease.joint_count = info.joint_count + 1;
      if (cull != SC_ERROR_MISSING_FIELD)
        CHECK_STATUS(sc_narrow_phase(model, ws, bind, vertex_count, 12, &crease, NULL, NULL, 0, &n_cull), SC_ERROR_JOINT_COUNT);
      crease.joint_matrices = NULL;
      crease.joint_count = 0;
      free(identity);
    }
    CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &crease, NULL, NULL, 0, &n_crease),
                 SC_OK_TRUNCATED);
    CHECK(n_crease > n_bind_crease);
    printf("%s: %u spheres; M2 pairs %u at bind, %u with the left arm pushed in (M1 %u); skin contacts %u (bind %u)\n",
           path, info.sphere_count, n_bind, n_m2, n_m1, n_crease, n_bind_crease);
    contacts = (sc_contact*)malloc(sizeof(sc_contact) * (n_crease + 1));
    depths = (sc_contact_depth*)malloc(sizeof(sc_contact_depth) * (n_crease + 1));
    if (!contacts || !depths) return;
    CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &crease, contacts, depths, n_crease, &count),
                 SC_OK);
    CHECK(count == n_crease);
    for (i = 0; i < n_crease; ++i) {
      const float* d = depths[i].direction;
      const float length = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      CHECK(contacts[i].triangle_a < info.triangle_count && contacts[i].triangle_b < info.triangle_count);
      CHECK(contacts[i].triangle_a != contacts[i].triangle_b && contacts[i].sphere_a <= contacts[i].sphere_b);
      CHECK(depths[i].depth >= 0.0f && depths[i].depth < 0.1f * height &&
            (fabsf(length - 1.0f) < 1e-3f || length == 0.0f));
    }
    /* Interleaved positions: the same contacts. */
    {
      sc_contact* again = (sc_contact*)malloc(sizeof(sc_contact) * n_crease);
      if (again) {
        CHECK_STATUS(sc_narrow_phase(model, ws, strided, vertex_count, 20, &crease, again, NULL, n_crease, &count),
                     SC_OK);
        CHECK(count == n_crease && memcmp(again, contacts, sizeof(sc_contact) * n_crease) == 0);
        free(again);
      }
    }
    /* A wider crease calls more pairs folds: never more contacts. A narrower one, or NaN: refused. */
    crease.crease = 2.0f * info.crease;
    CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &crease, contacts, NULL, n_crease, &n_wide),
                 SC_OK);
    CHECK(n_wide <= n_crease);
    crease.crease = 0.5f * info.crease;
    CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &crease, contacts, NULL, n_crease, &count),
                 SC_ERROR_INVALID_JOB);
    CHECK(count == 0);
    crease.crease = (float)NAN;
    CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &crease, contacts, NULL, n_crease, &count),
                 SC_ERROR_INVALID_JOB);
    crease.crease = 0.0f;
    /* Behind the proxy: the M2 pairs and the folds (sc_fold_pairs), a subset of the crease rule's contacts. */
    {
      uint32_t n_folds = 0, n_behind = 0, k;
      sc_pair* behind_pairs = (sc_pair*)malloc(sizeof(sc_pair) * (n_m2 + 1024));
      sc_contact* every = (sc_contact*)malloc(sizeof(sc_contact) * (n_crease + 1));
      sc_contact* behind = (sc_contact*)malloc(sizeof(sc_contact) * (n_crease + 1));
      CHECK_STATUS(sc_fold_pairs(model, ws, (float)NAN, NULL, 0, &n_folds), SC_ERROR_INVALID_JOB);
      CHECK_STATUS(sc_fold_pairs(model, ws, -1.0f, NULL, 0, &n_folds), SC_ERROR_INVALID_JOB);
      CHECK_STATUS(sc_fold_pairs(model, ws, 0.0f, NULL, 0, NULL), SC_ERROR_NULL_ARGUMENT);
      CHECK_STATUS(sc_fold_pairs(model, ws, 0.0f, NULL, 1, &n_folds), SC_ERROR_NULL_ARGUMENT);
      CHECK_STATUS(sc_fold_pairs(model, ws, 1e30f, NULL, 0, &n_folds), SC_OK);
      CHECK(n_folds == 0);
      if (behind_pairs && every && behind) {
        memcpy(behind_pairs, m2, sizeof(sc_pair) * n_m2);
        CHECK_STATUS(sc_fold_pairs(model, ws, 2.0f * info.contact_margin, behind_pairs + n_m2, 1024, &n_folds), SC_OK);
        for (k = 0; k < n_folds; ++k) CHECK(behind_pairs[n_m2 + k].a < behind_pairs[n_m2 + k].b);
        CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &crease, every, NULL, n_crease, &count),
                     SC_OK);
        crease.sphere_pairs = behind_pairs;
        crease.sphere_pair_count = n_m2 + n_folds;
        CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &crease, behind, NULL, n_crease, &n_behind),
                     SC_OK);
        CHECK(n_behind > 0 && n_behind <= n_crease);
        CHECK(AllAmong(behind, n_behind, every, n_crease));
        printf("%s: behind the M2 pairs and %u folds, %u of the %u skin contacts\n", path, n_folds, n_behind, n_crease);
        crease.sphere_pairs = NULL;
        crease.sphere_pair_count = 0;
      }
      free(behind_pairs);
      free(every);
      free(behind);
    }

    /* The asset's exclusions (NULL options = zero-initialised options), unrestricted, and restricted to the M2
     * pairs: the restricted contacts are among the unrestricted ones. */
    {
      sc_narrow_phase_options asset_pairs;
      sc_contact* all = NULL;
      memset(&asset_pairs, 0, sizeof(asset_pairs));
      CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &asset_pairs, NULL, NULL, 0, &n_asset),
                   n_asset ? SC_OK_TRUNCATED : SC_OK);
      CHECK(n_asset > 0);
      all = (sc_contact*)malloc(sizeof(sc_contact) * (n_asset + 1));
      if (all) {
        CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, NULL, all, NULL, n_asset, &n_default),
                     SC_OK);
        CHECK(n_default == n_asset);
        asset_pairs.sphere_pairs = m2;
        asset_pairs.sphere_pair_count = n_m2;
        free(contacts);
        contacts = (sc_contact*)malloc(sizeof(sc_contact) * (n_asset + 1));
        if (contacts) {
          CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &asset_pairs, contacts, NULL, n_asset,
                                       &n_restricted),
                       SC_OK);
          CHECK(n_restricted > 0 && n_restricted <= n_asset);
          CHECK(AllAmong(contacts, n_restricted, all, n_asset));
        }
        /* Errors of the options: a NULL pair list with a count, a bad pair, unknown exclusions. */
        asset_pairs.sphere_pairs = NULL;
        CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &asset_pairs, all, NULL, n_asset, &count),
                     SC_ERROR_NULL_ARGUMENT);
        {
          sc_pair bad;
          memset(&bad, 0, sizeof(bad));
          bad.a = 3;
          bad.b = 2;
          asset_pairs.sphere_pairs = &bad;
          asset_pairs.sphere_pair_count = 1;
          CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &asset_pairs, all, NULL, n_asset, &count),
                       SC_ERROR_INDEX_OUT_OF_RANGE);
        }
        asset_pairs.sphere_pairs = NULL;
        asset_pairs.sphere_pair_count = 0;
        asset_pairs.exclusions = (sc_exclusions)9;
        CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, &asset_pairs, all, NULL, n_asset, &count),
                     SC_ERROR_INVALID_JOB);
        free(all);
      }
    }
  }

  /* Argument errors of the narrow phase. */
  CHECK_STATUS(sc_narrow_phase(NULL, ws, deformed, vertex_count, 12, NULL, NULL, NULL, 0, &count),
               SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_narrow_phase(model, NULL, deformed, vertex_count, 12, NULL, NULL, NULL, 0, &count),
               SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_narrow_phase(model, ws, NULL, vertex_count, 12, NULL, NULL, NULL, 0, &count), SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, NULL, NULL, NULL, 0, NULL),
               SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 12, NULL, NULL, NULL, 5, &count),
               SC_ERROR_NULL_ARGUMENT);
  CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count + 1, 12, NULL, NULL, NULL, 0, &count),
               SC_ERROR_VERTEX_COUNT);
  CHECK_STATUS(sc_narrow_phase(model, ws, deformed, vertex_count, 6, NULL, NULL, NULL, 0, &count), SC_ERROR_STRIDE);
  CHECK_STATUS(sc_narrow_phase(model, ws, (const float*)((const char*)deformed + 2), vertex_count, 12, NULL, NULL, NULL,
                               0, &count),
               SC_ERROR_ALIGNMENT);

  /* NaN positions: the refit does not check them (NaN spheres never overlap: no pair); the narrow phase refuses. */
  for (v = 0; v < 3 * vertex_count; ++v) moved[v] = (float)NAN;
  CHECK_STATUS(sc_refit_vertices(model, ws, moved, vertex_count, 12), SC_OK);
  CHECK_STATUS(sc_detect(model, ws, SC_DETECT_M2, -1.0f, m2, bound_m2, &count), SC_OK);
  CHECK(count == 0);
  count = 7;
  CHECK_STATUS(sc_narrow_phase(model, ws, moved, vertex_count, 12, NULL, NULL, NULL, 0, &count),
               SC_ERROR_NON_FINITE_POSITIONS);
  CHECK(count == 0);

  sc_workspace_destroy(ws_plain);
  sc_workspace_destroy(ws);
  sc_model_destroy(plain);
  sc_model_destroy(model);
  free(depths);
  free(contacts);
  free(m2);
  free(m1);
  free(moved);
  free(strided);
  free(deformed);
  free(spheres);
  free(bind_spheres);
  free(bytes);
}

int main(int argc, char** argv) {
  if (argc == 4 && strcmp(argv[1], "golden") == 0) {
    TestGolden(argv[2], argv[3]);
  } else if (argc == 3 && strcmp(argv[1], "real") == 0) {
    if (!FileExists(argv[2])) {
      printf("SKIPPED: %s not found (its fixture bakes it from ../shared/data, which is absent)\n", argv[2]);
      return 0;
    }
    TestReal(argv[2]);
  } else {
    fprintf(stderr, "usage: c_api_c99 golden V3.sphc V1.sphc | c_api_c99 real ASSET.sphc\n");
    return 2;
  }
  printf("%d checks, %d failed\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}
