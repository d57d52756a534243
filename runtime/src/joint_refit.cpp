// JointRefitJob: sphere centres by linear blend skinning of their bind centres, see refit.h.
#include <cmath>
#include <cstdint>
#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#include <xmmintrin.h>
#endif

#include "internal.h"

namespace spherechain::runtime {

Status JointRefitJob::Check() const {
  if (!joint_matrices) return Status::kErrorNullArgument;
  if (Status s = Model::Internal::CheckPair(model, workspace); s != Status::kOk) return s;
  if (model->joint_count() == 0) return Status::kErrorMissingField;
  if (joint_count != model->joint_count()) return Status::kErrorJointCount;
  if (reinterpret_cast<uintptr_t>(joint_matrices) % alignof(float) != 0) return Status::kErrorAlignment;
  return Status::kOk;
}

Status JointRefitJob::Run() const {
  if (Status s = Check(); s != Status::kOk) return s;
  // Every matrix finite before anything is written: x · 0 is ±0 for a finite x and NaN for a NaN or
  // ±inf, and a sum of ±0 stays ±0 while a NaN stays NaN — so Σ x · 0 over all 12·#J floats is NaN
  // exactly when one of them is not finite (SSE2, four accumulators: one multiply and one add per four
  // floats, ~1,350 instructions for MakeHuman's 163 joints where the exponent test took ~2,700).
  {
    const uint32_t n = joint_count * kJointMatrixFloats;  // a multiple of 4
#if defined(__SSE2__) || defined(_M_X64)
    const __m128 zero = _mm_setzero_ps();
    __m128 a0 = zero, a1 = zero, a2 = zero, a3 = zero;
    const float* p = joint_matrices;
    uint32_t i = 0;
    for (; i + 16 <= n; i += 16) {
      a0 = _mm_add_ps(a0, _mm_mul_ps(_mm_loadu_ps(p + i), zero));
      a1 = _mm_add_ps(a1, _mm_mul_ps(_mm_loadu_ps(p + i + 4), zero));
      a2 = _mm_add_ps(a2, _mm_mul_ps(_mm_loadu_ps(p + i + 8), zero));
      a3 = _mm_add_ps(a3, _mm_mul_ps(_mm_loadu_ps(p + i + 12), zero));
    }
    for (; i < n; i += 4) a0 = _mm_add_ps(a0, _mm_mul_ps(_mm_loadu_ps(p + i), zero));
    const __m128 sum = _mm_add_ps(_mm_add_ps(a0, a1), _mm_add_ps(a2, a3));
    if (_mm_movemask_ps(_mm_cmpunord_ps(sum, sum)) != 0) return Status::kErrorNonFiniteJoints;
#else
    for (uint32_t i = 0; i < n; ++i)
      if (!std::isfinite(joint_matrices[i])) return Status::kErrorNonFiniteJoints;
#endif
  }
  const ModelArrays& ma = model->arrays();
  const uint16_t* joints = ma.sphere_joints;
  const float* weights = ma.sphere_joint_weights;
  float* x = workspace->mutable_x();
  float* y = workspace->mutable_y();
  float* z = workspace->mutable_z();
  float* r = workspace->mutable_r();
  const float* M = joint_matrices;
  const uint32_t S = model->sphere_count();
  for (uint32_t s = 0; s < S; ++s) {
    const float b[4] = {ma.bind_x[s], ma.bind_y[s], ma.bind_z[s], ma.bind_r[s]};
    const uint16_t* js = joints + 4 * s;
    const float* ws = weights + 4 * s;
    // Blend the matrices (influences by descending weight: stop at the first 0), then transform once.
#if defined(__SSE2__) || defined(_M_X64)
    const float* m = M + size_t{kJointMatrixFloats} * js[0];
    __m128 w = _mm_set1_ps(ws[0]);
    __m128 r0 = _mm_mul_ps(w, _mm_loadu_ps(m)), r1 = _mm_mul_ps(w, _mm_loadu_ps(m + 4)),
           r2 = _mm_mul_ps(w, _mm_loadu_ps(m + 8));
    for (int k = 1; k < 4 && ws[k] != 0.0f; ++k) {
      m = M + size_t{kJointMatrixFloats} * js[k];
      w = _mm_set1_ps(ws[k]);
      r0 = _mm_add_ps(r0, _mm_mul_ps(w, _mm_loadu_ps(m)));
      r1 = _mm_add_ps(r1, _mm_mul_ps(w, _mm_loadu_ps(m + 4)));
      r2 = _mm_add_ps(r2, _mm_mul_ps(w, _mm_loadu_ps(m + 8)));
    }
    const __m128 p = _mm_set_ps(1.0f, b[2], b[1], b[0]);
    __m128 a0 = _mm_mul_ps(r0, p), a1 = _mm_mul_ps(r1, p), a2 = _mm_mul_ps(r2, p), a3 = _mm_setzero_ps();
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
    alignas(16) float c[4];
    _mm_store_ps(c, _mm_add_ps(_mm_add_ps(a0, a1), _mm_add_ps(a2, a3)));
    x[s] = c[0];
    y[s] = c[1];
    z[s] = c[2];
#else
    const float* m = M + size_t{kJointMatrixFloats} * js[0];
    float blend[12];
    for (int i = 0; i < 12; ++i) blend[i] = ws[0] * m[i];
    for (int k = 1; k < 4 && ws[k] != 0.0f; ++k) {
      m = M + size_t{kJointMatrixFloats} * js[k];
      for (int i = 0; i < 12; ++i) blend[i] += ws[k] * m[i];
    }
    x[s] = blend[0] * b[0] + blend[1] * b[1] + blend[2] * b[2] + blend[3];
    y[s] = blend[4] * b[0] + blend[5] * b[1] + blend[6] * b[2] + blend[7];
    z[s] = blend[8] * b[0] + blend[9] * b[1] + blend[10] * b[2] + blend[11];
#endif
    r[s] = b[3];
  }
  return Status::kOk;
}

}  // namespace spherechain::runtime
