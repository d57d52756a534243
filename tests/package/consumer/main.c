/* consumer_c ASSET.sphc — a C program on the installed C API (spherechain::c): loads an asset, runs one refit
 * from the joint matrices (identity: the bind pose) and the broad phase, prints what it holds. Exit 0 when every
 * call succeeds, 1 otherwise (the message names the status). */
#include <stdio.h>
#include <stdlib.h>

#include "spherechain/spherechain.h"

int main(int argc, char** argv) {
  FILE* f;
  long size;
  void* bytes;
  sc_model* model = NULL;
  sc_workspace* ws = NULL;
  sc_model_info info;
  sc_status s;
  float* joints;
  sc_pair* pairs;
  uint32_t j, n = 0;
  if (argc != 2) return fprintf(stderr, "usage: consumer_c ASSET.sphc\n"), 2;
  if (!(f = fopen(argv[1], "rb")) || fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) <= 0 || fseek(f, 0, SEEK_SET) != 0)
    return fprintf(stderr, "error: cannot read '%s'\n", argv[1]), 1;
  bytes = malloc((size_t)size); /* malloc: 8-byte aligned, as the asset must be */
  if (!bytes || fread(bytes, 1, (size_t)size, f) != (size_t)size)
    return fprintf(stderr, "error: cannot read '%s'\n", argv[1]), 1;
  fclose(f);
  if (SC_FAILED(s = sc_model_create(bytes, (size_t)size, 0, &model)) ||
      SC_FAILED(s = sc_model_get_info(model, &info)) || SC_FAILED(s = sc_workspace_create(model, &ws)))
    return fprintf(stderr, "error: '%s': %s\n", argv[1], sc_status_string(s)), 1;
  joints = (float*)calloc(12 * (size_t)info.joint_count + 12, sizeof(float));
  pairs = (sc_pair*)malloc(sizeof(sc_pair) * sc_detect_bound(model, SC_DETECT_M2));
  if (!joints || !pairs) return 1;
  for (j = 0; j < info.joint_count; ++j) joints[12 * j] = joints[12 * j + 5] = joints[12 * j + 10] = 1.0f;
  if ((info.joint_count && SC_FAILED(s = sc_refit_joints(model, ws, joints, info.joint_count))) ||
      SC_FAILED(s = sc_detect(model, ws, SC_DETECT_M2, -1.0f, pairs, sc_detect_bound(model, SC_DETECT_M2), &n)))
    return fprintf(stderr, "error: %s\n", sc_status_string(s)), 1;
  printf("C: spheres %u chains %u joints %u m2_pairs %u\n", info.sphere_count, info.chain_count, info.joint_count, n);
  free(pairs);
  free(joints);
  sc_workspace_destroy(ws);
  sc_model_destroy(model);
  free(bytes);
  return 0;
}
