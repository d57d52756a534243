/* hello_c — the spherechain runtime from C (spherechain/spherechain.h, library spherechain::c): load a .sphc
 * asset, refit its spheres from a deformed vertex buffer, find the colliding sphere pairs (the broad phase) and
 * the exact skin contacts (the narrow phase), print them.
 *
 *   hello_c ASSET.sphc
 *
 * A game has its own skinned vertex buffer; here the asset's bind pose (sc_bind_positions) stands in for it,
 * copied into an interleaved vertex buffer (position, normal, uv), and the "animation" pushes the left arm into
 * the body. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "spherechain/spherechain.h"

typedef struct vertex { /* the game's vertex layout: the runtime reads the position through a stride */
  float position[3];
  float normal[3];
  float uv[2];
} vertex;

#define MAX_CONTACTS 4096 /* the narrow phase has no useful bound: size for the worst frame expected */

/* The whole file in malloc'ed memory (8-byte aligned, as the asset must be); NULL when it cannot be read. */
static void* read_file(const char* path, size_t* size) {
  FILE* f = fopen(path, "rb");
  void* bytes = NULL;
  long n;
  if (!f) return NULL;
  if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0 && (bytes = malloc((size_t)n))) {
    if (fread(bytes, 1, (size_t)n, f) == (size_t)n)
      *size = (size_t)n;
    else
      free(bytes), bytes = NULL;
  }
  fclose(f);
  return bytes;
}

static const char* sphere_region_name(const sc_model* model, uint32_t sphere) {
  uint32_t region = 0;
  return SC_SUCCEEDED(sc_sphere_region(model, sphere, &region)) ? sc_region_name(model, region) : "?";
}

/* The "animation": every vertex whose nearest bind sphere is a left_arm sphere moves 0.8 of the way from the
 * arm's centroid to the body's, across the body (the axes other than the height, the longest extent). */
static void push_left_arm(const sc_model* model, const float* spheres, uint32_t sphere_count, vertex* vb,
                          uint32_t vertex_count) {
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  double sum[2][3] = {{0, 0, 0}, {0, 0, 0}};
  uint32_t n[2] = {0, 0}, v, s;
  unsigned char* arm = (unsigned char*)calloc(vertex_count, 1);
  int up = 0, k;
  if (!arm) return;
  for (v = 0; v < vertex_count; ++v) {
    const float* p = vb[v].position;
    float best = INFINITY;
    uint32_t nearest = 0;
    for (s = 0; s < sphere_count; ++s) {
      const float* c = spheres + 4 * s;
      const float d =
          sqrtf((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) + (p[2] - c[2]) * (p[2] - c[2])) - c[3];
      if (d < best) best = d, nearest = s;
    }
    arm[v] = strcmp(sphere_region_name(model, nearest), "left_arm") == 0;
    for (k = 0; k < 3; ++k) {
      sum[arm[v]][k] += p[k];
      if (p[k] < lo[k]) lo[k] = p[k];
      if (p[k] > hi[k]) hi[k] = p[k];
    }
    ++n[arm[v]];
  }
  for (k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[up] - lo[up]) up = k;
  for (v = 0; v < vertex_count && n[0] && n[1]; ++v)
    for (k = 0; k < 3 && arm[v]; ++k)
      if (k != up) vb[v].position[k] -= (float)(0.8 * (sum[1][k] / n[1] - sum[0][k] / n[0]));
  free(arm);
}

int main(int argc, char** argv) {
  size_t size = 0;
  void* bytes;
  sc_model* model = NULL;
  sc_workspace* ws = NULL;
  sc_model_info info;
  sc_status s;
  const float* bind = NULL;
  uint32_t vertex_count = 0, pair_count = 0, contact_count = 0, i, deepest = 0, pair_bound = 0;
  float* spheres = NULL;
  vertex* vb = NULL;
  sc_pair* pairs = NULL;
  static sc_contact contacts[MAX_CONTACTS];
  static sc_contact_depth depths[MAX_CONTACTS];
  sc_narrow_phase_options skin = {SC_EXCLUSIONS_CREASE, 0.0f, NULL, 0, NULL, 0}; /* the skin's own contacts */
  int rc = 1;

  if (argc != 2) {
    fprintf(stderr, "usage: hello_c ASSET.sphc\n");
    return 2;
  }
  /* 1. Load, once per asset: the bytes stay alive (and unmodified) as long as the model. Model and workspace
   * are the only allocations; nothing after them allocates. */
  if (!(bytes = read_file(argv[1], &size))) {
    fprintf(stderr, "error: cannot read '%s'\n", argv[1]);
    return 1;
  }
  s = sc_model_create(bytes, size, SC_MODEL_NARROW_PHASE, &model);
  if (SC_FAILED(s)) {
    fprintf(stderr, "error: '%s': %s\n", argv[1], sc_status_string(s));
    free(bytes);
    return 1;
  }
  if (SC_FAILED(s = sc_model_get_info(model, &info)) || SC_FAILED(s = sc_workspace_create(model, &ws)) ||
      SC_FAILED(s = sc_bind_positions(model, &bind, &vertex_count))) {
    fprintf(stderr, "error: %s\n", sc_status_string(s));
    goto done;
  }
  /* The pair buffer's bytes in 64 bits: on a 32-bit target they overflow size_t past about 26,700 spheres. A
   * one-sphere asset has no pair: malloc(1) then, since malloc(0) may be NULL. */
  pair_bound = sc_detect_bound(model, SC_DETECT_M2);
  if ((uint64_t)pair_bound * sizeof(sc_pair) > SIZE_MAX) {
    fprintf(stderr, "error: %u sphere pairs do not fit this machine's memory\n", pair_bound);
    goto done;
  }
  spheres = (float*)malloc(sizeof(float) * 4 * info.sphere_count);
  vb = (vertex*)calloc(vertex_count, sizeof(vertex));
  pairs = (sc_pair*)malloc(pair_bound ? sizeof(sc_pair) * (size_t)pair_bound : 1); /* never truncated */
  if (!spheres || !vb || !pairs) {
    fprintf(stderr, "error: out of memory\n");
    goto done;
  }

  /* 2. The game's vertex buffer: the bind pose (and the bind spheres, to find the arm), the left arm pushed in. */
  for (i = 0; i < vertex_count; ++i) memcpy(vb[i].position, bind + 3 * i, sizeof(float) * 3);
  if (SC_FAILED(s = sc_workspace_spheres(ws, spheres, info.sphere_count, &i))) goto done;
  push_left_arm(model, spheres, info.sphere_count, vb, vertex_count);

  /* 3. Every frame: refit, broad phase (M2: all spheres), narrow phase (exact contacts, with depths). */
  if (SC_FAILED(s = sc_refit_vertices(model, ws, vb[0].position, vertex_count, sizeof(vertex))) ||
      SC_FAILED(
          s = sc_detect(model, ws, SC_DETECT_M2, -1.0f, pairs, pair_bound, &pair_count)) ||
      SC_FAILED(s = sc_narrow_phase(model, ws, vb[0].position, vertex_count, sizeof(vertex),
                                    info.has_crease ? &skin : NULL, contacts, depths, MAX_CONTACTS, &contact_count))) {
    fprintf(stderr, "error: %s\n", sc_status_string(s));
    goto done;
  }

  /* 4. Report: the pairs with their regions and the triangles behind them, then the contacts. */
  printf("%s: %u spheres, %u colliding pairs with the left arm pushed into the body\n", argv[1], info.sphere_count,
         pair_count);
  for (i = 0; i < pair_count; ++i) {
    const uint32_t* tris;
    uint32_t na = 0, nb = 0;
    sc_sphere_triangles(model, pairs[i].a, &tris, &na);
    sc_sphere_triangles(model, pairs[i].b, &tris, &nb);
    printf("  sphere %3u (%-10s) x sphere %3u (%-10s) depth %.3f  triangles %u + %u\n", pairs[i].a,
           sphere_region_name(model, pairs[i].a), pairs[i].b, sphere_region_name(model, pairs[i].b), pairs[i].depth, na,
           nb);
  }
  if (s == SC_OK_TRUNCATED) printf("  (more than %u contacts: the first %u kept)\n", MAX_CONTACTS, MAX_CONTACTS);
  if (contact_count > MAX_CONTACTS) contact_count = MAX_CONTACTS;
  for (i = 1; i < contact_count && info.has_crease; ++i)
    if (depths[i].depth > depths[deepest].depth) deepest = i;
  printf("%u skin contacts (intersecting triangle pairs)", contact_count);
  if (contact_count && info.has_crease)
    printf("; deepest: triangles %u x %u, depth %.3f", contacts[deepest].triangle_a, contacts[deepest].triangle_b,
           depths[deepest].depth);
  printf("\n");
  rc = 0;

done:
  free(pairs);
  free(vb);
  free(spheres);
  sc_workspace_destroy(ws);
  sc_model_destroy(model);
  free(bytes);
  return rc;
}
