// Exact triangle–triangle intersection: Guigue & Devillers 2003 on filtered exact orientation predicates
// (Shewchuk 1997). See triangle_intersect.h for the contract.
//
// Layout: (1) floating-point expansions, the exact arithmetic; (2) exact orient3d / orient2d on them,
// out of line (rare); (3) the filtered predicates, inline; (4) the 2D (coplanar) test; (5) the 3D test;
// (6) prepared triangles: a semi-static float filter (its error bound derived there) in front of (5).
//
// Why float inputs never break the arithmetic: coordinates converted to double are multiples of 2^-149
// with |x| < 2^128, so every difference is a multiple of 2^-149, every product of three differences a
// multiple of 2^-447 below 2^387: no overflow, no underflow (doubles are normal down to 2^-1022), hence
// the error bounds hold and TwoSum / TwoProduct are exact throughout.
//
// Floating-point environment: IEEE float and double with round-to-nearest and no extended precision
// (SSE2 and later, ARM, CUDA). Results flushed to zero (FTZ) do no harm to the double paths (no double
// result comes near 2^-1022), and section 6's bound covers underflowing float products and sums, gradual
// or flushed. One case it does not cover: under FTZ the float difference of two coordinates both below
// ~2^-101 in magnitude can flush a non-zero difference to 0, an error relative to nothing, which the
// bound's absolute terms do not reach; with gradual underflow (the IEEE default) such differences are
// exact. Character coordinates are nowhere near that; a caller running with FTZ on such input should
// use TrianglesIntersect on the floats (double filters only). Subnormal inputs read as
// zero (DAZ) are not supported. Contraction into FMA (-ffp-contract=fast) only removes roundings from the filtered
// expressions, so the bounds still hold; the error-free transformations keep their product out of reach
// (every product feeds std::fma). -ffast-math (reassociation) would break them: refused below.
#include "spherechain/runtime/triangle_intersect.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 2)
#define SPHERECHAIN_TRIANGLE_SSE2 1
#include <emmintrin.h>
#endif

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>  // section 7 (AVX-512 function targets)

#include "avx512_target.h"
#include "internal.h"
#endif

#if defined(__FAST_MATH__)
#error "triangle_intersect.cpp must not be compiled with -ffast-math: its exact arithmetic relies on IEEE rounding"
#endif
#if defined(FLT_EVAL_METHOD) && (FLT_EVAL_METHOD == 1 || FLT_EVAL_METHOD == 2)
#error "triangle_intersect.cpp needs double evaluated in double precision (x87 extended precision breaks TwoSum)"
#endif

#if defined(__GNUC__) || defined(__clang__)
#define SPHERECHAIN_NOINLINE __attribute__((noinline))
#elif defined(_MSC_VER)
#define SPHERECHAIN_NOINLINE __declspec(noinline)
#else
#define SPHERECHAIN_NOINLINE
#endif

namespace spherechain::runtime {

namespace {

// ---------------------------------------------------------------------------------------------------
// (1) Floating-point expansions (Shewchuk 1997 §2). An expansion is a sum of doubles, stored by
// increasing magnitude, pairwise non-overlapping (strongly, with round-to-nearest-even), zero components
// removed (Sum also takes inputs with zeros, as the two-product pairs of the short Minor); zero itself is
// the one component {0}. Its sign is the sign of its last (largest) component.

/// x + y = a + b exactly, x = fl(a + b) (Knuth's TwoSum: no precondition on |a|, |b|).
inline void TwoSum(double a, double b, double& x, double& y) {
  x = a + b;
  const double b_virtual = x - a;
  const double a_virtual = x - b_virtual;
  y = (a - a_virtual) + (b - b_virtual);
}

/// x + y = a − b exactly, x = fl(a − b).
inline void TwoDiff(double a, double b, double& x, double& y) {
  x = a - b;
  const double b_virtual = a - x;
  const double a_virtual = x + b_virtual;
  y = (a - a_virtual) + (b_virtual - b);
}

/// x + y = a · b exactly, x = fl(a · b) (the fused multiply-add returns the exact rounding error).
inline void TwoProduct(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

template <int N>
struct Expansion {
  double c[N];
  int n;
};

inline int Sign(double v) { return (v > 0) - (v < 0); }

template <int N>
int Sign(const Expansion<N>& e) {
  return Sign(e.c[e.n - 1]);
}

/// a − b as an expansion of one or two components.
inline Expansion<2> Diff(double a, double b) {
  Expansion<2> e;
  double x, y;
  TwoDiff(a, b, x, y);
  if (y != 0) {
    e.c[0] = y;
    e.c[1] = x;
    e.n = 2;
  } else {
    e.c[0] = x;
    e.n = 1;
  }
  return e;
}

template <int N>
void Negate(Expansion<N>& e) {
  for (int i = 0; i < e.n; ++i) e.c[i] = -e.c[i];
}

/// e + f: merge by magnitude, then one pass of TwoSum carrying the running sum upward
/// (Fast-Expansion-Sum with zero elimination, Shewchuk 1997 Theorem 13).
template <int A, int B>
Expansion<A + B> Sum(const Expansion<A>& e, const Expansion<B>& f) {
  Expansion<A + B> h;
  h.n = 0;
  int i = 0, j = 0;
  auto next = [&]() {
    if (j >= f.n || (i < e.n && std::fabs(e.c[i]) <= std::fabs(f.c[j]))) return e.c[i++];
    return f.c[j++];
  };
  double q = next();
  while (i < e.n || j < f.n) {
    double s, err;
    TwoSum(q, next(), s, err);
    if (err != 0) h.c[h.n++] = err;
    q = s;
  }
  if (q != 0 || h.n == 0) h.c[h.n++] = q;
  return h;
}

/// e · b (Scale-Expansion with zero elimination, Shewchuk 1997 Theorem 19).
template <int A>
Expansion<2 * A> Scale(const Expansion<A>& e, double b) {
  Expansion<2 * A> h;
  h.n = 0;
  double q, err;
  TwoProduct(e.c[0], b, q, err);
  if (err != 0) h.c[h.n++] = err;
  for (int i = 1; i < e.n; ++i) {
    double hi, lo, s;
    TwoProduct(e.c[i], b, hi, lo);
    TwoSum(q, lo, s, err);
    if (err != 0) h.c[h.n++] = err;
    TwoSum(hi, s, q, err);
    if (err != 0) h.c[h.n++] = err;
  }
  if (q != 0 || h.n == 0) h.c[h.n++] = q;
  return h;
}

/// e · f for f of at most two components (a coordinate difference).
template <int A>
Expansion<4 * A> Product(const Expansion<A>& e, const Expansion<2>& f) {
  const Expansion<2 * A> low = Scale(e, f.c[0]);
  if (f.n == 2) return Sum(low, Scale(e, f.c[1]));
  Expansion<4 * A> h;
  h.n = low.n;
  for (int i = 0; i < low.n; ++i) h.c[i] = low.c[i];
  return h;
}

/// u_i · v_j − u_j · v_i, exactly, for single doubles.
inline Expansion<4> Minor(double ui, double uj, double vi, double vj) {
  Expansion<2> left, right;
  TwoProduct(ui, vj, left.c[1], left.c[0]);
  TwoProduct(uj, vi, right.c[1], right.c[0]);
  left.n = right.n = 2;
  Negate(right);
  return Sum(left, right);
}

/// u_i · v_j − u_j · v_i, exactly.
inline Expansion<16> Minor(const Expansion<2>& ui, const Expansion<2>& uj, const Expansion<2>& vi,
                           const Expansion<2>& vj) {
  Expansion<8> right = Product(uj, vi);
  Negate(right);
  return Sum(Product(ui, vj), right);
}

// Shewchuk's error bounds (1997 §4.3 and his predicates.c; his epsilon is the unit roundoff).
constexpr double kEpsilon = 0x1p-53;                                   // unit roundoff of double
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;  // Shewchuk's ccwerrboundA
constexpr double kOrient3dBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;  // Shewchuk's o3derrboundA
constexpr double kOrient3dBoundB = (3.0 + 28.0 * kEpsilon) * kEpsilon;               // o3derrboundB
constexpr double kOrient3dBoundC = (26.0 + 288.0 * kEpsilon) * kEpsilon * kEpsilon;  // o3derrboundC
constexpr double kResultBound = (3.0 + 8.0 * kEpsilon) * kEpsilon;                   // resulterrbound

// ---------------------------------------------------------------------------------------------------
// (2) Exact predicates. Points are double[3] holding float values (so no product of up to three
// differences, nor any rounding error of one, leaves double's normal range: no underflow, no overflow).
// Stages: (a) the plain double evaluation with the rounding error of every operation computed (TwoDiff,
// TwoProduct, TwoSum): when all are zero, the double value is the determinant — the usual case for the
// exact zeros of coplanar, touching or shared-vertex inputs on coarse coordinates (the role CGAL's
// interval filter plays); (b, orient3d only) Shewchuk's adaptive stages B and C; (c) otherwise the full
// expansion evaluation, exact always.

/// a·b − c·d in double; clears `exact` if a rounding happened.
inline double CheckedMinor(double a, double b, double c, double d, bool& exact) {
  double p, p_err, q, q_err, m, m_err;
  TwoProduct(a, b, p, p_err);
  TwoProduct(c, d, q, q_err);
  TwoDiff(p, q, m, m_err);
  exact &= (p_err == 0) & (q_err == 0) & (m_err == 0);
  return m;
}

/// b − a in double; clears `exact` if it rounded.
inline double CheckedDiff(double b, double a, bool& exact) {
  double x, err;
  TwoDiff(b, a, x, err);
  exact &= err == 0;
  return x;
}

/// Sign of ((b − a) × (c − a)) · (d − a), exactly: > 0 when d lies on the side the right-handed normal
/// of (a, b, c) points to.
/// Stage (c) alone: the sign of ((b − a) × (c − a)) · (d − a) from the full expansions.
int Orient3dExpansions(const double* a, const double* b, const double* c, const double* d) {
  Expansion<2> eu[3], ev[3], ew[3];
  for (int k = 0; k < 3; ++k) {
    eu[k] = Diff(b[k], a[k]);
    ev[k] = Diff(c[k], a[k]);
    ew[k] = Diff(d[k], a[k]);
  }
  const Expansion<64> tx = Product(Minor(eu[1], eu[2], ev[1], ev[2]), ew[0]);
  const Expansion<64> ty = Product(Minor(eu[2], eu[0], ev[2], ev[0]), ew[1]);
  const Expansion<64> tz = Product(Minor(eu[0], eu[1], ev[0], ev[1]), ew[2]);
  return Sign(Sum(Sum(tx, ty), tz));
}

/// Which stage of Orient3dExact decided (detail::ExactOrientation reports it to tests).
enum class Orient3dStage : int { kErrorFree = 0, kRoundedDifferences = 1, kTailCorrection = 2, kExpansions = 3 };

SPHERECHAIN_NOINLINE int Orient3dExact(const double* a, const double* b, const double* c, const double* d,
                                       uint64_t* counter, Orient3dStage* stage = nullptr) {
  if (counter) ++*counter;
  Orient3dStage unused;
  Orient3dStage& decided = stage ? *stage : unused;
  decided = Orient3dStage::kErrorFree;
  // (a) error-free double evaluation.
  // The rounded differences and their tails (x + tail = exactly the difference): stage (b)'s C uses the tails.
  double u[3], v[3], w[3], du[3], dv[3], dw[3];
  for (int k = 0; k < 3; ++k) {
    TwoDiff(b[k], a[k], u[k], du[k]);
    TwoDiff(c[k], a[k], v[k], dv[k]);
    TwoDiff(d[k], a[k], w[k], dw[k]);
  }
  const bool differences_exact = (du[0] == 0) & (du[1] == 0) & (du[2] == 0) & (dv[0] == 0) & (dv[1] == 0) &
                                 (dv[2] == 0) & (dw[0] == 0) & (dw[1] == 0) & (dw[2] == 0);
  bool exact = differences_exact;
  if (exact) {
    const double mx = CheckedMinor(u[1], v[2], u[2], v[1], exact);
    const double my = CheckedMinor(u[2], v[0], u[0], v[2], exact);
    const double mz = CheckedMinor(u[0], v[1], u[1], v[0], exact);
    double tx, ty, tz, t_err[3], sum, sum_err, det, det_err;
    TwoProduct(w[0], mx, tx, t_err[0]);
    TwoProduct(w[1], my, ty, t_err[1]);
    TwoProduct(w[2], mz, tz, t_err[2]);
    TwoSum(tx, ty, sum, sum_err);
    TwoSum(sum, tz, det, det_err);
    if (exact & (t_err[0] == 0) & (t_err[1] == 0) & (t_err[2] == 0) & (sum_err == 0) & (det_err == 0)) return Sign(det);
  }
  {
    decided = Orient3dStage::kRoundedDifferences;
    // (b) Shewchuk 1997 §4.3, orient3dadapt's stages B and C, on the transposed matrix (his rows a, b, c
    // are our columns: his adx, ady, adz are u[0], v[0], w[0]). B: the determinant of the rounded
    // differences exactly (a short expansion): the answer when no difference rounded, else certified by
    // bound B. C: that estimate plus the first-order terms of the differences' tails in double, certified
    // by bound C (ε² relative to the permanent). Mixed magnitudes (1e-40 beside 1e38 in a mutated bind
    // pose) defeat (a) and B but rarely C; what neither certifies goes on to (c).
    const Expansion<4> mx = Minor(u[1], u[2], v[1], v[2]);
    const Expansion<4> my = Minor(u[2], u[0], v[2], v[0]);
    const Expansion<4> mz = Minor(u[0], u[1], v[0], v[1]);
    const Expansion<24> det = Sum(Sum(Scale(mx, w[0]), Scale(my, w[1])), Scale(mz, w[2]));
    if (differences_exact) return Sign(det);
    double estimate = 0;
    for (int i = 0; i < det.n; ++i) estimate += det.c[i];
    double permanent = 0;
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      permanent += (std::fabs(u[i] * v[j]) + std::fabs(v[i] * u[j])) * std::fabs(w[k]);
    }
    const double bound_b = kOrient3dBoundB * permanent;
    if ((estimate >= bound_b) | (-estimate >= bound_b)) return Sign(estimate);
    decided = Orient3dStage::kTailCorrection;
    const double bound_c = kOrient3dBoundC * permanent + kResultBound * std::fabs(estimate);
    // The three terms summed first ((T0 + T1) + T2), then added in one rounding: his order, which his
    // bound counts on (adding each to the estimate would round three times at the estimate's size).
    double tails = 0;
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      tails += w[k] * ((u[i] * dv[j] + v[j] * du[i]) - (v[i] * du[j] + u[j] * dv[i])) +
               dw[k] * (u[i] * v[j] - v[i] * u[j]);
    }
    estimate += tails;
    if ((estimate >= bound_c) | (-estimate >= bound_c)) return Sign(estimate);
  }
  // (c) expansions.
  decided = Orient3dStage::kExpansions;
  return Orient3dExpansions(a, b, c, d);
}

/// Sign of (b_i − a_i)(c_j − a_j) − (b_j − a_j)(c_i − a_i), exactly: the orientation of (a, b, c)
/// projected on the coordinate plane (i, j); for (i, j) = (k+1, k+2) mod 3 it is the sign of component
/// k of (b − a) × (c − a).
SPHERECHAIN_NOINLINE int Orient2dExact(const double* a, const double* b, const double* c, int i, int j,
                                       uint64_t* counter) {
  if (counter) ++*counter;
  bool exact = true;
  const double ui = CheckedDiff(b[i], a[i], exact), uj = CheckedDiff(b[j], a[j], exact);
  const double vi = CheckedDiff(c[i], a[i], exact), vj = CheckedDiff(c[j], a[j], exact);
  if (exact) {
    const double det = CheckedMinor(ui, vj, uj, vi, exact);
    if (exact) return Sign(det);
  }
  return Sign(Minor(Diff(b[i], a[i]), Diff(b[j], a[j]), Diff(c[i], a[i]), Diff(c[j], a[j])));
}

// ---------------------------------------------------------------------------------------------------
// (3) Filtered predicates: the double evaluation, certified by Shewchuk's a-priori bound A (relative to
// the permanent, the same expression with absolute values), else the exact evaluation above. The bounds
// hold for the rounded differences computed here (they include the rounding of the differences).


/// A vertex: the float coordinates, converted (exactly) to double.
struct Vec3 {
  double c[3];
};

inline Vec3 Load(const float* f) {
  return {{static_cast<double>(f[0]), static_cast<double>(f[1]), static_cast<double>(f[2])}};
}

/// The plane of triangle (a, b, c) prepared for many orient3d(a, b, c, ·): n = (b − a) × (c − a) in
/// double and, per component, the permanent of its 2×2 minor (|u_i v_j| + |u_j v_i|).
struct Plane {
  double n[3];
  double perm[3];
};

inline Plane MakePlane(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double ux = b.c[0] - a.c[0], uy = b.c[1] - a.c[1], uz = b.c[2] - a.c[2];
  const double vx = c.c[0] - a.c[0], vy = c.c[1] - a.c[1], vz = c.c[2] - a.c[2];
  const double xl = uy * vz, xr = uz * vy, yl = uz * vx, yr = ux * vz, zl = ux * vy, zr = uy * vx;
  return {{xl - xr, yl - yr, zl - zr},
          {std::fabs(xl) + std::fabs(xr), std::fabs(yl) + std::fabs(yr), std::fabs(zl) + std::fabs(zr)}};
}

/// Filtered orient3d(a, b, c, d) for the plane of (a, b, c): the double value and its error bound.
struct Filtered {
  double det, bound;
};

inline Filtered Side(const Plane& p, const Vec3& a, const Vec3& d) {
  const double wx = d.c[0] - a.c[0], wy = d.c[1] - a.c[1], wz = d.c[2] - a.c[2];
  return {wx * p.n[0] + wy * p.n[1] + wz * p.n[2],
          kOrient3dBound * (std::fabs(wx) * p.perm[0] + std::fabs(wy) * p.perm[1] + std::fabs(wz) * p.perm[2])};
}

/// True when the three filtered values are certified strictly positive, or all strictly negative.
inline bool CertifiedOneSide(const Filtered& f0, const Filtered& f1, const Filtered& f2) {
  const bool above = (f0.det > f0.bound) & (f1.det > f1.bound) & (f2.det > f2.bound);
  const bool below = (f0.det < -f0.bound) & (f1.det < -f1.bound) & (f2.det < -f2.bound);
  return above | below;
}

/// Sign of orient3d(a, b, c, d) from its filtered value, exact when the bound does not certify it.
/// Branch-free in the certified case (the sign itself is data, the fallback is rare).
inline int Resolve(const Filtered& f, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, uint64_t* counter) {
  const int sign = int(f.det > f.bound) - int(f.det < -f.bound);
  if (sign != 0) [[likely]]
    return sign;
  return Orient3dExact(a.c, b.c, c.c, d.c, counter);
}

/// Sign of ((b − a) × (c − a)) · (d − a).
inline int Orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, uint64_t* counter) {
  return Resolve(Side(MakePlane(a, b, c), a, d), a, b, c, d, counter);
}

/// Sign of component k of the plane's normal (b − a) × (c − a): the orient2d of the triangle (a, b, c)
/// projected along axis k.
inline int NormalSign(const Plane& p, int k, const Vec3& a, const Vec3& b, const Vec3& c, uint64_t* counter) {
  const double bound = kOrient2dBound * p.perm[k];
  if (p.n[k] > bound) return 1;
  if (p.n[k] < -bound) return -1;
  return Orient2dExact(a.c, b.c, c.c, (k + 1) % 3, (k + 2) % 3, counter);
}

/// True when the triangle (a, b, c) of plane p has exactly zero area (every normal component exactly 0).
inline bool Degenerate(const Plane& p, const Vec3& a, const Vec3& b, const Vec3& c, uint64_t* counter) {
  if ((std::fabs(p.n[0]) > kOrient2dBound * p.perm[0]) | (std::fabs(p.n[1]) > kOrient2dBound * p.perm[1]) |
      (std::fabs(p.n[2]) > kOrient2dBound * p.perm[2]))
    return false;  // a component certified non-zero: the usual exit
  for (int k = 0; k < 3; ++k)
    if (NormalSign(p, k, a, b, c, counter) != 0) return false;
  return true;
}

/// Sign of (b_i − a_i)(c_j − a_j) − (b_j − a_j)(c_i − a_i).
inline int Orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int i, int j, uint64_t* counter) {
  const double l = (b.c[i] - a.c[i]) * (c.c[j] - a.c[j]);
  const double r = (b.c[j] - a.c[j]) * (c.c[i] - a.c[i]);
  const double det = l - r;
  const double bound = kOrient2dBound * (std::fabs(l) + std::fabs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return Orient2dExact(a.c, b.c, c.c, i, j, counter);
}

/// True when every coordinate is finite (|x| ≤ max is false for NaN and ±Inf).
inline bool AllFinite(const Vec3* v, int count) {
  bool finite = true;
  for (int i = 0; i < count; ++i)
    for (int k = 0; k < 3; ++k) finite &= std::fabs(v[i].c[k]) <= std::numeric_limits<double>::max();
  return finite;
}

// ---------------------------------------------------------------------------------------------------
// (4) Coplanar triangles: project along an axis where the (common) plane's normal component is exactly
// non-zero — an affine bijection of the plane onto the coordinate plane, so intersection is preserved —
// and test the closed 2D triangles by separating edges: two closed convex polygons are disjoint iff the
// supporting line of an edge of one has the other strictly on its outer side (the edges of their
// Minkowski difference are edges of either). 2 + up to 18 exact-when-needed orient2d.

/// True when some edge of `tri` (orientation `orientation`, ±1, in the projection (i, j)) has the three
/// vertices of `other` strictly on its outer side.
inline bool EdgeSeparates(const Vec3* const tri[3], int orientation, const Vec3* const other[3], int i, int j,
                          uint64_t* counter) {
  for (int e = 0; e < 3; ++e) {
    const Vec3& a = *tri[e];
    const Vec3& b = *tri[(e + 1) % 3];
    bool separated = true;
    for (int v = 0; v < 3 && separated; ++v) separated = orientation * Orient2d(a, b, *other[v], i, j, counter) < 0;
    if (separated) return true;
  }
  return false;
}

SPHERECHAIN_NOINLINE bool CoplanarIntersect(const Plane& plane1, const Vec3* const t1[3], const Vec3* const t2[3],
                                            uint64_t* counter) {
  // Drop the axis of the largest |normal component| of triangle 1 (the best conditioned projection);
  // exact non-zeroness decides, the magnitudes only order the tries.
  const double m0 = std::fabs(plane1.n[0]), m1 = std::fabs(plane1.n[1]), m2 = std::fabs(plane1.n[2]);
  int order[3] = {0, 1, 2};
  if (m1 > m0 && m1 >= m2) {
    order[0] = 1;
    order[1] = 0;
  } else if (m2 > m0 && m2 > m1) {
    order[0] = 2;
    order[2] = 0;
  }
  int axis = -1, orientation1 = 0;
  for (int t = 0; t < 3 && orientation1 == 0; ++t) {
    axis = order[t];
    orientation1 = NormalSign(plane1, axis, *t1[0], *t1[1], *t1[2], counter);
  }
  if (orientation1 == 0) return false;  // unreachable: triangle 1 is not degenerate (checked before)
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const int orientation2 = Orient2d(*t2[0], *t2[1], *t2[2], i, j, counter);
  if (orientation2 == 0) return false;  // unreachable: triangle 2 is not degenerate and lies in the plane
  return !EdgeSeparates(t1, orientation1, t2, i, j, counter) && !EdgeSeparates(t2, orientation2, t1, i, j, counter);
}

// ---------------------------------------------------------------------------------------------------
// (5) The 3D test (Guigue & Devillers 2003 §3).

/// The canonical vertex of a triangle whose vertices have the orientations s0, s1, s2 w.r.t. the other
/// plane (not all strictly on one side, not all zero): the apex k alone on its side, the other two on
/// the opposite closed side, so that the plane cuts the triangle along a segment with ends on the edges
/// leaving the apex. `flip` is −1 when the apex is on the negative side (or on the plane with both others
/// positive): the other triangle is then reoriented so that the apex is on its non-negative side.
struct Apex {
  int8_t k, flip;
};

constexpr Apex FindApex(int s0, int s1, int s2) {
  const int s[3] = {s0, s1, s2};
  for (int k = 0; k < 3; ++k)
    if (s[k] != 0 && s[(k + 1) % 3] != s[k] && s[(k + 2) % 3] != s[k]) return {int8_t(k), int8_t(s[k])};
  // Two vertices strictly on one side, the third on the plane: the third is the apex.
  const int k = s[0] == 0 ? 0 : (s[1] == 0 ? 1 : 2);
  return {int8_t(k), int8_t(-s[(k + 1) % 3])};
}

/// FindApex for the 27 sign patterns, indexed by 9(s0 + 1) + 3(s1 + 1) + (s2 + 1): a load, not branches
/// on data (the patterns that never reach it hold harmless values).
struct ApexTable {
  Apex entry[27];
  constexpr ApexTable() : entry{} {
    for (int i = 0; i < 27; ++i) entry[i] = FindApex(i / 9 - 1, i / 3 % 3 - 1, i % 3 - 1);
  }
};
constexpr ApexTable kApex;

/// The canonical form (Guigue & Devillers 2003, §3) for exact orientations s1 of triangle 1's vertices
/// (0, 1, 2) against plane 2 and s2 of triangle 2's (3, 4, 5) against plane 1, neither all equal nor all
/// zero, both triangles non-degenerate: the vertices a1, b1, c1, a2, b2, c2 (indices) of the interval
/// test, which is: Orient3d(a1, b1, a2, b2) ≤ 0 and Orient3d(a1, c1, c2, a2) ≤ 0 (the segments T1 ∩ L and
/// T2 ∩ L on the line L = plane1 ∩ plane2 overlap iff neither starts after the other ends).
struct Canonical {
  int a1, b1, c1, a2, b2, c2;
};

constexpr Canonical CanonicalForm(const int s1[3], const int s2[3]) {
  // Triangle 1 rotated so its apex a1 is alone on the non-negative side of (oriented) plane 2, edges
  // a1b1, a1c1 crossing it; likewise triangle 2 w.r.t. (oriented) plane 1. Rotations keep
  // orientations; a swap of the two non-apex vertices reverses the triangle's plane.
  const Apex apex1 = kApex.entry[9 * (s1[0] + 1) + 3 * (s1[1] + 1) + (s1[2] + 1)];
  // Triangle 2 reversed (q2, r2 swapped) when apex1.flip < 0, so that a1 is on its non-negative side.
  const int swap2 = apex1.flip < 0;
  const int order2[3] = {0, 1 + swap2, 2 - swap2};
  const Apex apex2 = kApex.entry[9 * (s2[order2[0]] + 1) + 3 * (s2[order2[1]] + 1) + (s2[order2[2]] + 1)];
  // Triangle 1 reversed (b1, c1 swapped) when apex2.flip < 0, so that a2 is on its non-negative side.
  const int swap1 = apex2.flip < 0;
  return {apex1.k, (apex1.k + 1 + swap1) % 3, (apex1.k + 2 - swap1) % 3,
          3 + order2[apex2.k], 3 + order2[(apex2.k + 1) % 3], 3 + order2[(apex2.k + 2) % 3]};
}

/// CanonicalForm for the 64 patterns of non-zero signs, indexed by the positive ones as bits: triangle
/// 1's vertices in bits 0..2, triangle 2's in 3..5 (a load instead of a chain of dependent lookups; the
/// all-equal patterns, which never reach it, hold harmless values).
struct CanonicalTable {
  Canonical entry[64];
  constexpr CanonicalTable() : entry{} {
    for (int m = 0; m < 64; ++m) {
      const int s1[3] = {m & 1 ? 1 : -1, m & 2 ? 1 : -1, m & 4 ? 1 : -1};
      const int s2[3] = {m & 8 ? 1 : -1, m & 16 ? 1 : -1, m & 32 ? 1 : -1};
      entry[m] = CanonicalForm(s1, s2);
    }
  }
};
constexpr CanonicalTable kCanonical;

/// Everything after the two filtered early exits, for finite input: exact signs where the filter was
/// unsure, the exact early exits, degenerate triangles, the coplanar case, the canonical form and the
/// interval test. v: p1, q1, r1, p2, q2, r2; plane1, plane2: MakePlane of each; f1, f2: the filtered
/// orientations of triangle 1's vertices against plane 2 (Side(plane2, p2, ·)) and of 2's against 1.
SPHERECHAIN_NOINLINE bool IntersectRest(const Vec3 v[6], const Plane& plane1, const Plane& plane2,
                                        const Filtered f1[3], const Filtered f2[3], uint64_t* counter) {
  const Vec3* t1[3] = {&v[0], &v[1], &v[2]};
  const Vec3* t2[3] = {&v[3], &v[4], &v[5]};
  // The convention: a degenerate triangle (no plane: every orientation against it is exactly 0, so the
  // strict exits never fire for it) never intersects.
  auto degenerate = [&] {
    return Degenerate(plane1, v[0], v[1], v[2], counter) || Degenerate(plane2, v[3], v[4], v[5], counter);
  };
  int s1[3], s2[3];
  for (int k = 0; k < 3; ++k) s1[k] = Resolve(f1[k], v[3], v[4], v[5], v[k], counter);
  if ((s1[0] == s1[1]) & (s1[1] == s1[2]) & (s1[0] != 0)) return false;
  // Triangle 1 in plane 2: coplanar (then triangle 2 lies in plane 1 too, its orientations need not be
  // resolved), unless a triangle is degenerate.
  if ((s1[0] == 0) & (s1[1] == 0) & (s1[2] == 0)) return !degenerate() && CoplanarIntersect(plane1, t1, t2, counter);
  for (int k = 0; k < 3; ++k) s2[k] = Resolve(f2[k], v[0], v[1], v[2], v[3 + k], counter);
  if ((s2[0] == s2[1]) & (s2[1] == s2[2]) & (s2[0] != 0)) return false;
  if (degenerate()) return false;

  const Canonical k = CanonicalForm(s1, s2);
  if (Orient3d(v[k.a1], v[k.b1], v[k.a2], v[k.b2], counter) > 0) return false;
  return Orient3d(v[k.a1], v[k.c1], v[k.c2], v[k.a2], counter) <= 0;
}

/// IntersectRest for float input: non-finite coordinates (NaN/Inf never pass a certified comparison, so
/// the exits before returned false already or we get here) answer false before any exact evaluation.
SPHERECHAIN_NOINLINE bool IntersectRestChecked(const Vec3 v[6], uint64_t* counter) {
  if (!AllFinite(v, 6)) return false;
  const Plane plane1 = MakePlane(v[0], v[1], v[2]), plane2 = MakePlane(v[3], v[4], v[5]);
  const Filtered f1[3] = {Side(plane2, v[3], v[0]), Side(plane2, v[3], v[1]), Side(plane2, v[3], v[2])};
  const Filtered f2[3] = {Side(plane1, v[0], v[3]), Side(plane1, v[0], v[4]), Side(plane1, v[0], v[5])};
  return IntersectRest(v, plane1, plane2, f1, f2, counter);
}

/// The whole test. The hot part — two planes, six filtered orientations, the two early exits — is
/// straight-line double arithmetic in registers; the rest is out of line.
inline bool Intersect(const float* p1, const float* q1, const float* r1, const float* p2, const float* q2,
                      const float* r2, uint64_t* counter) {
  const Vec3 P1 = Load(p1), Q1 = Load(q1), R1 = Load(r1), P2 = Load(p2), Q2 = Load(q2), R2 = Load(r2);
  // Triangle 1 against the plane of triangle 2, then 2 against 1: strictly on one side ⇒ disjoint.
  const Plane plane2 = MakePlane(P2, Q2, R2);
  const Filtered a = Side(plane2, P2, P1), b = Side(plane2, P2, Q1), c = Side(plane2, P2, R1);
  if (CertifiedOneSide(a, b, c)) return false;
  const Plane plane1 = MakePlane(P1, Q1, R1);
  const Filtered d = Side(plane1, P1, P2), e = Side(plane1, P1, Q2), f = Side(plane1, P1, R2);
  if (CertifiedOneSide(d, e, f)) return false;
  const Vec3 v[6] = {P1, Q1, R1, P2, Q2, R2};
  return IntersectRestChecked(v, counter);
}

// ---------------------------------------------------------------------------------------------------
// (6) Prepared triangles and their semi-static float filter.
//
// The value to certify is D(x) = N · (x − p), N = (q − p) × (r − p) exactly (x, p, q, r floats: exact
// reals). PrepareTriangle computes in float u = q − p, v = r − p, per component i (j, k the next two)
// a_i = u_j v_k, b_i = u_k v_j, n_i = a_i − b_i, P_i = |a_i| + |b_i|, S = Σ P_i, and δ = n · p
// ((n_x p_x + n_y p_y) + n_z p_z). The filter computes in float e(x) = ((n_x x_x + n_y x_y) + n_z x_z) − δ.
// With u = 2^-24, γ_k = ku/(1 − ku), M_x = max_i |x_i|, M_p = max_i |p_i|, and "tiny" the absolute
// errors of underflow, gradual or flushed to zero (≤ 2^-126 per product or sum; differences of
// coordinates are exact when subnormal, flushed ones being the FTZ exception at the top of the file):
//   |n_i − N_i| ≤ η_i = 4.01u P_i + 3·2^-126          (rounded differences, products and difference),
//   |n_i| ≤ 1.0001 P_i,   e(x) − D(x) = [e(x) − (n · x − δ)] + (n − N) · (x − p) + (n · p − δ),
//   |e(x) − (n · x − δ)| ≤ γ4 (Σ|n_i||x_i| + |δ|) + 7·2^-126,   |n · p − δ| ≤ γ3 Σ|n_i||p_i| + 3·2^-126,
//   |δ| ≤ 1.0003 S M_p + 3·2^-126,   |(n − N) · (x − p)| ≤ Σ η_i (M_x + M_p),
// so |e(x) − D(x)| ≤ 8.02u S M_x + 11.02u S M_p + 9·2^-126 (M_x + M_p) + 13·2^-126 ≤ G M_x + A with
// G = 8.25u S + 2^-122 and A = (11.25u S + 2^-122) M_p + 2^-120, rounded up to floats with a 2^-20
// relative margin, which also covers the two roundings of the bound's own evaluation fl(fl(G M_x) + A).
// Then e > bound certifies D > 0 and e < −bound certifies D < 0; NaN compares false (uncertain). A fused
// multiply-add (contraction) only removes roundings. No overflow: the filter is live only for
// |coordinates| ≤ 2^40 (then P_i ≤ 2^83, every term of e stays below 2^126); otherwise G, A and M are +∞
// and nothing is certified. The same η_i certifies a non-zero area: |n_i| > η_i for some i ⇒ N ≠ 0.

constexpr double kFloatUnit = 0x1p-24;
constexpr float kFilterMaxCoordinate = 0x1p40f;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

/// A float ≥ v ≥ 0 (v finite, below 2^124): v with a 2^-20 margin, rounded to float.
inline float RoundUp(double v) { return static_cast<float>(v * (1.0 + 0x1p-20)); }

/// The float filter (see above) on the three vertices of t against the plane of p: bits 0..2 the
/// vertices certified strictly above, bits 4..6 those certified strictly below. Four lanes, the fourth
/// (the error terms) ignored.
inline uint32_t FloatSides(const PreparedTriangle& t, const PreparedTriangle& p) {
  const float bound = p.x[3] * t.z[3] + p.y[3];
#if SPHERECHAIN_TRIANGLE_SSE2
  __m128 e = _mm_mul_ps(_mm_set1_ps(p.plane[0]), _mm_load_ps(t.x));
  e = _mm_add_ps(e, _mm_mul_ps(_mm_set1_ps(p.plane[1]), _mm_load_ps(t.y)));
  e = _mm_add_ps(e, _mm_mul_ps(_mm_set1_ps(p.plane[2]), _mm_load_ps(t.z)));
  e = _mm_sub_ps(e, _mm_set1_ps(p.plane[3]));
  const __m128 b = _mm_set1_ps(bound);
  const uint32_t above = static_cast<uint32_t>(_mm_movemask_ps(_mm_cmpgt_ps(e, b))) & 7;
  const uint32_t below = static_cast<uint32_t>(_mm_movemask_ps(_mm_cmplt_ps(e, _mm_sub_ps(_mm_setzero_ps(), b)))) & 7;
  return above | below << 4;
#else
  uint32_t sides = 0;
  for (int k = 0; k < 3; ++k) {
    float e = p.plane[0] * t.x[k];
    e += p.plane[1] * t.y[k];
    e += p.plane[2] * t.z[k];
    e -= p.plane[3];
    sides |= uint32_t{e > bound} << k | uint32_t{e < -bound} << (4 + k);
  }
  return sides;
#endif
}

/// +1 / −1 when FloatSides certifies all three vertices above / below, else 0.
inline int OneSide(uint32_t sides) { return int((sides & 7) == 7) - int((sides >> 4) == 7); }

/// Orient3d(a, b, c, d) of float points whose |coordinates| are at most 2^40, evaluated in float as
/// MakePlane and Side do in double, certified by Shewchuk's orient3d bound A for float ((7 + 56u)u
/// relative to the permanent, u = 2^-24; 8u here) plus 2^-70 for underflow of products and sums
/// (gradual or flushed: at most ~2^-81 at that range; flushed differences: see the top of the file):
/// +1 / −1 when certified, 0 when not (then the caller evaluates exactly).
inline int FloatOrient3d(const float* a, const float* b, const float* c, const float* d) {
  const float ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const float vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const float wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  const float xl = uy * vz, xr = uz * vy, yl = uz * vx, yr = ux * vz, zl = ux * vy, zr = uy * vx;
  const float det = wx * (xl - xr) + wy * (yl - yr) + wz * (zl - zr);
  const float permanent = std::fabs(wx) * (std::fabs(xl) + std::fabs(xr)) + std::fabs(wy) * (std::fabs(yl) + std::fabs(yr)) +
                          std::fabs(wz) * (std::fabs(zl) + std::fabs(zr));
  const float bound = 8.0f * float(kFloatUnit) * permanent + 0x1p-70f;
  return int(det > bound) - int(det < -bound);
}

/// What Intersect does after its float-input checks, on prepared (finite, non-degenerate) triangles:
/// the filtered double orientations, then IntersectRest. For the rare pairs with a vertex the float
/// filter could not place (near the other plane).
SPHERECHAIN_NOINLINE bool IntersectPreparedDouble(const PreparedTriangle& t1, const PreparedTriangle& t2,
                                                  uint64_t* counter) {
  const Vec3 v[6] = {{{t1.x[0], t1.y[0], t1.z[0]}}, {{t1.x[1], t1.y[1], t1.z[1]}}, {{t1.x[2], t1.y[2], t1.z[2]}},
                     {{t2.x[0], t2.y[0], t2.z[0]}}, {{t2.x[1], t2.y[1], t2.z[1]}}, {{t2.x[2], t2.y[2], t2.z[2]}}};
  const Plane plane2 = MakePlane(v[3], v[4], v[5]);
  const Filtered f1[3] = {Side(plane2, v[3], v[0]), Side(plane2, v[3], v[1]), Side(plane2, v[3], v[2])};
  if (CertifiedOneSide(f1[0], f1[1], f1[2])) return false;
  const Plane plane1 = MakePlane(v[0], v[1], v[2]);
  const Filtered f2[3] = {Side(plane1, v[0], v[3]), Side(plane1, v[0], v[4]), Side(plane1, v[0], v[5])};
  if (CertifiedOneSide(f2[0], f2[1], f2[2])) return false;
  return IntersectRest(v, plane1, plane2, f1, f2, counter);
}

/// The exact Orient3d of four vertices of the prepared pair (indices 0..5: t1's p, q, r, then t2's).
SPHERECHAIN_NOINLINE int PreparedOrient3dExact(const PreparedTriangle* const t[2], int a, int b, int c, int d,
                                               uint64_t* counter) {
  auto vertex = [&](int i) {
    const PreparedTriangle& p = *t[i / 3];
    return Vec3{{p.x[i % 3], p.y[i % 3], p.z[i % 3]}};
  };
  return Orient3d(vertex(a), vertex(b), vertex(c), vertex(d), counter);
}

/// Intersect on prepared (finite, non-degenerate) triangles after the float filter both ways (sides1:
/// FloatSides(t1, t2), sides2: FloatSides(t2, t1), neither all on one side). When it certified the side
/// of every vertex (none near the other plane: the usual case), the canonical form and the interval
/// test follow on those signs with float-filtered orientations (exact ones where that filter is
/// unsure); otherwise IntersectPreparedDouble.
inline bool IntersectPreparedRest(const PreparedTriangle& t1, const PreparedTriangle& t2, uint32_t sides1,
                                  uint32_t sides2, uint64_t* counter) {
  if (((((sides1 | sides1 >> 4) & 7) == 7) & (((sides2 | sides2 >> 4) & 7) == 7)) == 0) [[unlikely]]
    return IntersectPreparedDouble(t1, t2, counter);
  // Every side certified, so the filter is live: |coordinates| ≤ 2^40, as FloatOrient3d needs. Both
  // orientations evaluated (independent: they overlap), then decided in the interval test's order.
  const PreparedTriangle* const t[2] = {&t1, &t2};
  auto vertex = [&](int i, float out[3]) {
    const PreparedTriangle& p = *t[i >= 3];
    const int k = i >= 3 ? i - 3 : i;
    out[0] = p.x[k], out[1] = p.y[k], out[2] = p.z[k];
  };
  const Canonical& k = kCanonical.entry[(sides1 & 7) | (sides2 & 7) << 3];
  float a1[3], b1[3], c1[3], a2[3], b2[3], c2[3];
  vertex(k.a1, a1), vertex(k.b1, b1), vertex(k.c1, c1), vertex(k.a2, a2), vertex(k.b2, b2), vertex(k.c2, c2);
  int first = FloatOrient3d(a1, b1, a2, b2);
  int second = FloatOrient3d(a1, c1, c2, a2);
  if (first == 0) first = PreparedOrient3dExact(t, k.a1, k.b1, k.a2, k.b2, counter);
  if (first > 0) return false;
  if (second == 0) second = PreparedOrient3dExact(t, k.a1, k.c1, k.c2, k.a2, counter);
  return second <= 0;
}

/// The hot part: the float filter both ways, in registers; the rest out of line.
inline bool IntersectPrepared(const PreparedTriangle& t1, const PreparedTriangle& t2, uint64_t* counter) {
  const uint32_t sides1 = FloatSides(t1, t2);
  if (OneSide(sides1) != 0) return false;
  const uint32_t sides2 = FloatSides(t2, t1);
  if (OneSide(sides2) != 0) return false;
  return IntersectPreparedRest(t1, t2, sides1, sides2, counter);
}

}  // namespace

bool TrianglesIntersect(const float p1[3], const float q1[3], const float r1[3], const float p2[3], const float q2[3],
                        const float r2[3]) {
  return Intersect(p1, q1, r1, p2, q2, r2, nullptr);
}

bool TriangleIsDegenerate(const float p[3], const float q[3], const float r[3]) {
  const Vec3 v[3] = {Load(p), Load(q), Load(r)};
  if (!AllFinite(v, 3)) return false;
  return Degenerate(MakePlane(v[0], v[1], v[2]), v[0], v[1], v[2], nullptr);
}

bool PrepareTriangle(const float p[3], const float q[3], const float r[3], PreparedTriangle* out) {
  // The float plane and its bounds (section 6).
  float n[3], perm[3], delta, m_p, m;
  bool finite;
#if SPHERECHAIN_TRIANGLE_SSE2
  auto load3 = [](const float* v) {  // x, y, z, 0: reads exactly three floats, 4-byte aligned
    double xy;
    std::memcpy(&xy, v, sizeof xy);
    return _mm_movelh_ps(_mm_castpd_ps(_mm_set_sd(xy)), _mm_load_ss(v + 2));
  };
  const __m128 P = load3(p), Q = load3(q), R = load3(r);
  const __m128 U = _mm_sub_ps(Q, P), V = _mm_sub_ps(R, P);
  // Component i of A: u_j v_k, of B: u_k v_j ((i, j, k) = (x, y, z) rotated): the products MakePlane takes.
  const __m128 A = _mm_mul_ps(_mm_shuffle_ps(U, U, _MM_SHUFFLE(3, 0, 2, 1)), _mm_shuffle_ps(V, V, _MM_SHUFFLE(3, 1, 0, 2)));
  const __m128 B = _mm_mul_ps(_mm_shuffle_ps(U, U, _MM_SHUFFLE(3, 1, 0, 2)), _mm_shuffle_ps(V, V, _MM_SHUFFLE(3, 0, 2, 1)));
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m128 N = _mm_sub_ps(A, B), PERM = _mm_add_ps(_mm_andnot_ps(sign, A), _mm_andnot_ps(sign, B));
  alignas(16) float nv[4], pv[4], np[4];
  _mm_store_ps(nv, N);
  _mm_store_ps(pv, PERM);
  _mm_store_ps(np, _mm_mul_ps(N, P));
  for (int k = 0; k < 3; ++k) n[k] = nv[k], perm[k] = pv[k];
  delta = (np[0] + np[1]) + np[2];
  const __m128 abs_p = _mm_andnot_ps(sign, P);
  __m128 mx = _mm_max_ps(abs_p, _mm_max_ps(_mm_andnot_ps(sign, Q), _mm_andnot_ps(sign, R)));
  mx = _mm_max_ps(mx, _mm_shuffle_ps(mx, mx, _MM_SHUFFLE(1, 0, 3, 2)));
  mx = _mm_max_ps(mx, _mm_shuffle_ps(mx, mx, _MM_SHUFFLE(2, 3, 0, 1)));
  __m128 mp = _mm_max_ps(abs_p, _mm_shuffle_ps(abs_p, abs_p, _MM_SHUFFLE(1, 0, 3, 2)));
  mp = _mm_max_ps(mp, _mm_shuffle_ps(mp, mp, _MM_SHUFFLE(2, 3, 0, 1)));
  m = _mm_cvtss_f32(mx), m_p = _mm_cvtss_f32(mp);
  // x − x is 0 for finite x, NaN for NaN and ±Inf (then max may have dropped it: checked apart).
  const __m128 zero = _mm_setzero_ps();
  finite = _mm_movemask_ps(_mm_and_ps(_mm_and_ps(_mm_cmpeq_ps(_mm_sub_ps(P, P), zero), _mm_cmpeq_ps(_mm_sub_ps(Q, Q), zero)),
                                      _mm_cmpeq_ps(_mm_sub_ps(R, R), zero))) == 15;
#else
  const float ux = q[0] - p[0], uy = q[1] - p[1], uz = q[2] - p[2];
  const float vx = r[0] - p[0], vy = r[1] - p[1], vz = r[2] - p[2];
  const float xl = uy * vz, xr = uz * vy, yl = uz * vx, yr = ux * vz, zl = ux * vy, zr = uy * vx;
  n[0] = xl - xr, n[1] = yl - yr, n[2] = zl - zr;
  perm[0] = std::fabs(xl) + std::fabs(xr), perm[1] = std::fabs(yl) + std::fabs(yr), perm[2] = std::fabs(zl) + std::fabs(zr);
  delta = (n[0] * p[0] + n[1] * p[1]) + n[2] * p[2];
  m_p = std::max(std::fabs(p[0]), std::max(std::fabs(p[1]), std::fabs(p[2])));
  m = std::max(m_p, std::max(std::max(std::max(std::fabs(q[0]), std::fabs(q[1])), std::fabs(q[2])),
                             std::max(std::max(std::fabs(r[0]), std::fabs(r[1])), std::fabs(r[2]))));
  // x − x is 0 for finite x, NaN for NaN and ±Inf.
  const float nan_probe = (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]) + (q[0] - q[0]) + (q[1] - q[1]) +
                          (q[2] - q[2]) + (r[0] - r[0]) + (r[1] - r[1]) + (r[2] - r[2]);
  finite = nan_probe == 0.0f;
#endif
  const bool live = finite && m <= kFilterMaxCoordinate;
  const double sum = double(perm[0]) + double(perm[1]) + double(perm[2]);
  const float g = live ? RoundUp(8.25 * kFloatUnit * sum + 0x1p-122) : kInfinity;
  const float a = live ? RoundUp((11.25 * kFloatUnit * sum + 0x1p-122) * double(m_p) + 0x1p-120) : kInfinity;
  const float x[4] = {p[0], q[0], r[0], g}, y[4] = {p[1], q[1], r[1], a}, z[4] = {p[2], q[2], r[2], live ? m : kInfinity};
  const float plane[4] = {n[0], n[1], n[2], delta};
  std::memcpy(out->x, x, sizeof x);
  std::memcpy(out->y, y, sizeof y);
  std::memcpy(out->z, z, sizeof z);
  std::memcpy(out->plane, plane, sizeof plane);
  if (!finite) return false;
  // A component beyond its error bound η_i (4.02u rounds up the bound's own evaluation) certifies a
  // non-zero area where nothing overflowed (live); else (slivers, underflow, huge coordinates) the exact
  // test decides.
  constexpr float kEta = 4.02f * float(kFloatUnit);
  if (live && ((std::fabs(n[0]) > kEta * perm[0] + 0x1p-124f) | (std::fabs(n[1]) > kEta * perm[1] + 0x1p-124f) |
               (std::fabs(n[2]) > kEta * perm[2] + 0x1p-124f)))
    return true;
  const Vec3 w[3] = {Load(p), Load(q), Load(r)};
  return !Degenerate(MakePlane(w[0], w[1], w[2]), w[0], w[1], w[2], nullptr);
}

bool TrianglesIntersect(const PreparedTriangle& a, const PreparedTriangle& b) { return IntersectPrepared(a, b, nullptr); }

// ---------------------------------------------------------------------------------------------------
// (7) The float filter on 16 triangles at once (AVX-512, by lane; the crease rule's AVX-512 sweep). Every
// value is PrepareTriangle's (SSE2 path) and FloatSides' for the same triangle, by the same float and double
// operations in the same order (no contraction: the runtime builds with -ffp-contract=off), so a lane
// certified here is a triangle PrepareTriangle accepts, and a pair rejected here is a pair
// IntersectPrepared rejects in its float filter: the answers and counts of the scalar path, unchanged.
#if defined(__GNUC__) && defined(__x86_64__)
SPHERECHAIN_AVX512_BEGIN

uint32_t PrepareFilter16(float* f, uint32_t lanes) {
  const __m512 sign = _mm512_set1_ps(-0.0f), zero = _mm512_setzero_ps();
  auto row = [&](int r) { return _mm512_loadu_ps(f + 16 * r); };
  auto abs = [&](__m512 v) { return _mm512_andnot_ps(sign, v); };
  const __m512 px = row(0), py = row(1), pz = row(2), qx = row(3), qy = row(4), qz = row(5), rx = row(6), ry = row(7),
               rz = row(8);
  const __m512 ux = _mm512_sub_ps(qx, px), uy = _mm512_sub_ps(qy, py), uz = _mm512_sub_ps(qz, pz);
  const __m512 vx = _mm512_sub_ps(rx, px), vy = _mm512_sub_ps(ry, py), vz = _mm512_sub_ps(rz, pz);
  // A_i = u_j v_k, B_i = u_k v_j ((i, j, k) = (x, y, z) rotated), as PrepareTriangle.
  const __m512 ax = _mm512_mul_ps(uy, vz), bx = _mm512_mul_ps(uz, vy);
  const __m512 ay = _mm512_mul_ps(uz, vx), by = _mm512_mul_ps(ux, vz);
  const __m512 az = _mm512_mul_ps(ux, vy), bz = _mm512_mul_ps(uy, vx);
  const __m512 nx = _mm512_sub_ps(ax, bx), ny = _mm512_sub_ps(ay, by), nz = _mm512_sub_ps(az, bz);
  const __m512 permx = _mm512_add_ps(abs(ax), abs(bx)), permy = _mm512_add_ps(abs(ay), abs(by)),
               permz = _mm512_add_ps(abs(az), abs(bz));
  const __m512 delta =
      _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(nx, px), _mm512_mul_ps(ny, py)), _mm512_mul_ps(nz, pz));
  const __m512 m_p = _mm512_max_ps(abs(px), _mm512_max_ps(abs(py), abs(pz)));
  const __m512 m = _mm512_max_ps(
      m_p, _mm512_max_ps(_mm512_max_ps(_mm512_max_ps(abs(qx), abs(qy)), abs(qz)),
                         _mm512_max_ps(_mm512_max_ps(abs(rx), abs(ry)), abs(rz))));
  __mmask16 ok = static_cast<__mmask16>(lanes);
  for (const __m512 c : {px, py, pz, qx, qy, qz, rx, ry, rz})  // x − x is 0 for finite x
    ok = _mm512_mask_cmp_ps_mask(ok, _mm512_sub_ps(c, c), zero, _CMP_EQ_OQ);
  ok = _mm512_mask_cmp_ps_mask(ok, m, _mm512_set1_ps(kFilterMaxCoordinate), _CMP_LE_OQ);  // live
  // A normal component beyond its error bound certifies a non-zero area (PrepareTriangle's kEta test);
  // the other lanes (slivers, padding) are left to PrepareTriangle.
  const __m512 eta = _mm512_set1_ps(4.02f * float(kFloatUnit)), tiny = _mm512_set1_ps(0x1p-124f);
  const __mmask16 area = _mm512_cmp_ps_mask(abs(nx), _mm512_add_ps(_mm512_mul_ps(eta, permx), tiny), _CMP_GT_OQ) |
                         _mm512_cmp_ps_mask(abs(ny), _mm512_add_ps(_mm512_mul_ps(eta, permy), tiny), _CMP_GT_OQ) |
                         _mm512_cmp_ps_mask(abs(nz), _mm512_add_ps(_mm512_mul_ps(eta, permz), tiny), _CMP_GT_OQ);
  ok &= area;
  // G and A in double, eight lanes at a time, rounded up into float as RoundUp.
  __m256 g[2], a[2];
  for (int h = 0; h < 2; ++h) {
    auto half = [&](__m512 v) {
      return _mm512_cvtps_pd(h ? _mm512_extractf32x8_ps(v, 1) : _mm512_castps512_ps256(v));
    };
    const __m512d sum = _mm512_add_pd(_mm512_add_pd(half(permx), half(permy)), half(permz));
    const __m512d up = _mm512_set1_pd(1.0 + 0x1p-20);
    const __m512d gv = _mm512_add_pd(_mm512_mul_pd(_mm512_set1_pd(8.25 * kFloatUnit), sum), _mm512_set1_pd(0x1p-122));
    g[h] = _mm512_cvtpd_ps(_mm512_mul_pd(gv, up));
    const __m512d av = _mm512_add_pd(_mm512_mul_pd(_mm512_set1_pd(11.25 * kFloatUnit), sum), _mm512_set1_pd(0x1p-122));
    a[h] = _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_add_pd(_mm512_mul_pd(av, half(m_p)), _mm512_set1_pd(0x1p-120)), up));
  }
  _mm512_storeu_ps(f + 16 * 9, nx), _mm512_storeu_ps(f + 16 * 10, ny), _mm512_storeu_ps(f + 16 * 11, nz);
  _mm512_storeu_ps(f + 16 * 12, delta);
  _mm512_storeu_ps(f + 16 * 13, _mm512_insertf32x8(_mm512_castps256_ps512(g[0]), g[1], 1));
  _mm512_storeu_ps(f + 16 * 14, _mm512_insertf32x8(_mm512_castps256_ps512(a[0]), a[1], 1));
  _mm512_storeu_ps(f + 16 * 15, m);
  return ok;
}

uint32_t FilterRejects16(const float* t, uint32_t i, const float* u) {
  auto lane = [&](int r) { return _mm512_set1_ps(t[16 * r + i]); };
  auto row = [&](int r) { return _mm512_loadu_ps(u + 16 * r); };
  const __m512 zero = _mm512_setzero_ps();
  // One direction of FloatSides: `corners` (x, y, z of three vertices) against `plane` (n, δ), beyond
  // ±bound; all three strictly on one side rejects.
  auto one_side = [&](const __m512* corners, const __m512* plane, __m512 bound) {
    const __m512 below = _mm512_sub_ps(zero, bound);
    __mmask16 above_all = 0xffff, below_all = 0xffff;
    for (int k = 0; k < 3; ++k) {
      __m512 e = _mm512_mul_ps(plane[0], corners[3 * k]);
      e = _mm512_add_ps(e, _mm512_mul_ps(plane[1], corners[3 * k + 1]));
      e = _mm512_add_ps(e, _mm512_mul_ps(plane[2], corners[3 * k + 2]));
      e = _mm512_sub_ps(e, plane[3]);
      above_all &= _mm512_cmp_ps_mask(e, bound, _CMP_GT_OQ);
      below_all &= _mm512_cmp_ps_mask(e, below, _CMP_LT_OQ);
    }
    return static_cast<uint32_t>(above_all | below_all);
  };
  // t's vertices against each u's plane: bound G_u · M_t + A_u (FloatSides(t, u)).
  const __m512 t_corners[9] = {lane(0), lane(1), lane(2), lane(3), lane(4), lane(5), lane(6), lane(7), lane(8)};
  const __m512 u_plane[4] = {row(9), row(10), row(11), row(12)};
  const uint32_t first = one_side(t_corners, u_plane, _mm512_add_ps(_mm512_mul_ps(row(13), lane(15)), row(14)));
  // Each u's vertices against t's plane: bound G_t · M_u + A_t (FloatSides(u, t)).
  const __m512 u_corners[9] = {row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7), row(8)};
  const __m512 t_plane[4] = {lane(9), lane(10), lane(11), lane(12)};
  return first | one_side(u_corners, t_plane, _mm512_add_ps(_mm512_mul_ps(lane(13), row(15)), lane(14)));
}
SPHERECHAIN_AVX512_END
#endif

namespace detail {

bool TrianglesIntersectCounted(const PreparedTriangle& a, const PreparedTriangle& b, uint64_t* exact_evaluations) {
  return IntersectPrepared(a, b, exact_evaluations);
}

int FloatPlaneSide(const PreparedTriangle& t, const PreparedTriangle& plane_of) {
  return OneSide(FloatSides(t, plane_of));
}

int FloatOrientation(const float a[3], const float b[3], const float c[3], const float d[3]) {
  for (const float* p : {a, b, c, d})
    for (int k = 0; k < 3; ++k)
      if (!(std::fabs(p[k]) <= kFilterMaxCoordinate)) return 0;  // out of the filter's range (or NaN)
  return FloatOrient3d(a, b, c, d);
}

bool TrianglesIntersectCounted(const float p1[3], const float q1[3], const float r1[3], const float p2[3],
                               const float q2[3], const float r2[3], uint64_t* exact_evaluations) {
  return Intersect(p1, q1, r1, p2, q2, r2, exact_evaluations);
}

int ExactOrientation(const float a[3], const float b[3], const float c[3], const float d[3], int* stage) {
  const Vec3 A = Load(a), B = Load(b), C = Load(c), D = Load(d);
  Orient3dStage decided = Orient3dStage::kErrorFree;
  const int sign = Orient3dExact(A.c, B.c, C.c, D.c, nullptr, &decided);
  if (stage) *stage = static_cast<int>(decided);
  return sign;
}

int ExpansionOrientation(const float a[3], const float b[3], const float c[3], const float d[3]) {
  const Vec3 A = Load(a), B = Load(b), C = Load(c), D = Load(d);
  return Orient3dExpansions(A.c, B.c, C.c, D.c);
}

}  // namespace detail

}  // namespace spherechain::runtime
