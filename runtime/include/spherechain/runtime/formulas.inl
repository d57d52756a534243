// spherechain runtime — bodies of the per-frame formulas (see formulas.h), generic over a lane type.
//
// No include guard, no includes: this file is included inside a namespace that provides `Ops` — a type
// with `V` (a float or a vector of floats), `M` (its comparison mask) and static Set1, Sqrt, Gt, Lt, And,
// Blend — once for the scalar host / device path (formulas.h, namespace formulas, ScalarOps) and once per
// SIMD instruction set (runtime/src/kernels.cpp, namespaces sse, avx and avx512, so that each copy is
// compiled for its instruction set; avx512's mask type M is a __mmask16). V must support + − × ÷
// lane-wise (IEEE single precision, no FMA).
//
// Inputs are the four pivot-polygon centroids p_k (k = 0..3) of a sphere, one lane per sphere, in model
// space and source units (Asset.pivot_vertices → TriangleCentroid).

/// The pivot frame of p0..p3 (refit.h, BuildPivotFrame):
///   o = 0.25 · (((p0 + p1) + p2) + p3)
///   x = (p1 − p0) / |p1 − p0|
///   w = 0.5 (p2 + p3) − 0.5 (p0 + p1);  y = (w − (w·x) x) / |w − (w·x) x|      (Gram–Schmidt)
///   z = x × y
/// Returns the lanes whose frame is defined: |p1 − p0| and the residual |w − (w·x) x| both
/// > eps = 1e-6 · (1 + max_k |p_k − o|) (the max computed as sqrt(max_k |p_k − o|²): sqrt is
/// monotonic and correctly rounded, so it is the same float; NaN distances are skipped). Lanes not
/// returned hold o and unspecified axes. Cost: ~60 flops a lane, inline.
template <class Ops>
SPHERECHAIN_HD_INLINE typename Ops::M PivotFrameLanes(const typename Ops::V px[4], const typename Ops::V py[4],
                                                      const typename Ops::V pz[4], typename Ops::V o[3],
                                                      typename Ops::V axes[3][3]) {
  using V = typename Ops::V;
  using M = typename Ops::M;
  const V quarter = Ops::Set1(0.25f), half = Ops::Set1(0.5f);
  o[0] = quarter * (px[0] + px[1] + px[2] + px[3]);
  o[1] = quarter * (py[0] + py[1] + py[2] + py[3]);
  o[2] = quarter * (pz[0] + pz[1] + pz[2] + pz[3]);
  V max_d2 = Ops::Set1(0.0f);
  for (int k = 0; k < 4; ++k) {
    const V dx = px[k] - o[0], dy = py[k] - o[1], dz = pz[k] - o[2];
    const V d2 = dx * dx + dy * dy + dz * dz;
    max_d2 = Ops::Blend(Ops::Gt(d2, max_d2), d2, max_d2);
  }
  const V eps = Ops::Set1(1e-6f) * (Ops::Set1(1.0f) + Ops::Sqrt(max_d2));
  V xx = px[1] - px[0], xy = py[1] - py[0], xz = pz[1] - pz[0];
  const V xl = Ops::Sqrt(xx * xx + xy * xy + xz * xz);
  const M x_ok = Ops::Gt(xl, eps);
  xx = xx / xl, xy = xy / xl, xz = xz / xl;
  V wx = half * (px[2] + px[3]) - half * (px[0] + px[1]);
  V wy = half * (py[2] + py[3]) - half * (py[0] + py[1]);
  V wz = half * (pz[2] + pz[3]) - half * (pz[0] + pz[1]);
  const V wdx = wx * xx + wy * xy + wz * xz;
  wx = wx - wdx * xx, wy = wy - wdx * xy, wz = wz - wdx * xz;
  const V yl = Ops::Sqrt(wx * wx + wy * wy + wz * wz);
  const M ok = Ops::And(x_ok, Ops::Gt(yl, eps));
  wx = wx / yl, wy = wy / yl, wz = wz / yl;
  axes[0][0] = xx, axes[0][1] = xy, axes[0][2] = xz;
  axes[1][0] = wx, axes[1][1] = wy, axes[1][2] = wz;
  axes[2][0] = xy * wz - xz * wy;
  axes[2][1] = xz * wx - xx * wz;
  axes[2][2] = xx * wy - xy * wx;
  return ok;
}

/// Frame coordinates → model space: c = ((o + l0·x) + l1·y) + l2·z (refit.h, PivotFrameToModel).
template <class Ops>
SPHERECHAIN_HD_INLINE typename Ops::V FrameToModelLane(const typename Ops::V o[3], const typename Ops::V axes[3][3],
                                                       typename Ops::V lx, typename Ops::V ly, typename Ops::V lz,
                                                       int k) {
  return o[k] + lx * axes[0][k] + ly * axes[1][k] + lz * axes[2][k];
}

/// Mean distance from c to p0..p3: 0.25 · (((d0 + d1) + d2) + d3), d_k = |c − p_k| (refit.h,
/// PivotMeanDistance).
template <class Ops>
SPHERECHAIN_HD_INLINE typename Ops::V PivotMeanDistanceLanes(const typename Ops::V px[4], const typename Ops::V py[4],
                                                             const typename Ops::V pz[4], typename Ops::V cx,
                                                             typename Ops::V cy, typename Ops::V cz) {
  using V = typename Ops::V;
  V d[4];
  for (int k = 0; k < 4; ++k) {
    const V dx = cx - px[k], dy = cy - py[k], dz = cz - pz[k];
    d[k] = Ops::Sqrt(dx * dx + dy * dy + dz * dz);
  }
  return Ops::Set1(0.25f) * (d[0] + d[1] + d[2] + d[3]);
}

/// The refit of a sphere (§5.1, RefitJob): from its pivot centroids p0..p3 and its per-asset data
/// (Model: PivotFrame.local_center l, PivotFrame.centroid_offset f, radius_scale = bind radius /
/// PivotFrame.mean_distance):
///   kPivotFrame (frame_mode): c = o + R l, falling back per lane to kPaper when the frame is degenerate;
///   kPaper: c = o + f (the bind centre moved by the pivots' mean displacement);
///   r = radius_scale · PivotMeanDistance(p, c).
/// Writes c (out[0..2]) and r (out[3]). Cost: ~120 flops a lane, inline.
template <class Ops>
SPHERECHAIN_HD_INLINE void RefitLanes(const typename Ops::V px[4], const typename Ops::V py[4],
                                      const typename Ops::V pz[4], typename Ops::V lx, typename Ops::V ly,
                                      typename Ops::V lz, typename Ops::V fx, typename Ops::V fy, typename Ops::V fz,
                                      typename Ops::V radius_scale, bool frame_mode, typename Ops::V out[4]) {
  using V = typename Ops::V;
  V c[3];
  const V f[3] = {fx, fy, fz};
  if (frame_mode) {
    V o[3], axes[3][3];
    const typename Ops::M ok = PivotFrameLanes<Ops>(px, py, pz, o, axes);
    for (int k = 0; k < 3; ++k) c[k] = Ops::Blend(ok, FrameToModelLane<Ops>(o, axes, lx, ly, lz, k), o[k] + f[k]);
  } else {  // the origin of PivotFrameLanes, the same expression
    const V quarter = Ops::Set1(0.25f);
    c[0] = quarter * (px[0] + px[1] + px[2] + px[3]) + f[0];
    c[1] = quarter * (py[0] + py[1] + py[2] + py[3]) + f[1];
    c[2] = quarter * (pz[0] + pz[1] + pz[2] + pz[3]) + f[2];
  }
  out[0] = c[0], out[1] = c[1], out[2] = c[2];
  out[3] = radius_scale * PivotMeanDistanceLanes<Ops>(px, py, pz, c[0], c[1], c[2]);
}

/// The overlap test of §5.2 (11 operations) between sphere a and sphere b, radii already grown by the
/// contact margin: ‖c_b − c_a‖² < (r_b + r_a)², with d = c_b − c_a. False when any input is NaN.
template <class Ops>
SPHERECHAIN_HD_INLINE typename Ops::M OverlapLanes(typename Ops::V ax, typename Ops::V ay, typename Ops::V az,
                                                   typename Ops::V ar, typename Ops::V bx, typename Ops::V by,
                                                   typename Ops::V bz, typename Ops::V br) {
  using V = typename Ops::V;
  const V dx = bx - ax, dy = by - ay, dz = bz - az, rr = br + ar;
  return Ops::Lt(dx * dx + dy * dy + dz * dz, rr * rr);
}

/// Penetration depth of two spheres r_a + r_b − ‖c_b − c_a‖, as the detection reports it
/// (Collision::depth) [Units: source units]: with grow == 0 on the spheres' own radii (M1); with a
/// margin grow ≠ 0 computed on the grown radii and the margins taken off again,
/// ((r_a + m) + (r_b + m) − ‖·‖) − 2m (M2's historical rounding, kept bit for bit).
template <class Ops>
SPHERECHAIN_HD_INLINE typename Ops::V SphereDepth(typename Ops::V ax, typename Ops::V ay, typename Ops::V az,
                                                  typename Ops::V ar, typename Ops::V bx, typename Ops::V by,
                                                  typename Ops::V bz, typename Ops::V br, float grow) {
  using V = typename Ops::V;
  const V dx = bx - ax, dy = by - ay, dz = bz - az;
  const V d = Ops::Sqrt(dx * dx + dy * dy + dz * dz);
  if (grow != 0.0f) {
    const V g = Ops::Set1(grow);
    return (ar + g) + (br + g) - d - Ops::Set1(2.0f * grow);
  }
  return ar + br - d;
}
