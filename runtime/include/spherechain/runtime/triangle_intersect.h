// spherechain runtime — exact triangle–triangle intersection (the narrow phase's only geometric test).
//
// Guigue & Devillers 2003 ("Fast and robust triangle-triangle overlap test using orientation
// predicates", J. Graphics Tools 8(1)): only the signs of orientation determinants decide, never a
// constructed point. Each determinant is evaluated in double with a floating-point filter (the
// a-priori error bounds of Shewchuk 1997, "Adaptive precision floating-point arithmetic and fast robust
// geometric predicates", orient3d/orient2d bound A); when the filter cannot certify the sign it is
// recomputed exactly: first the plain double evaluation with the rounding error of every operation
// computed (TwoDiff / TwoSum / TwoProduct via std::fma; all zero ⇒ the value is exact), else with
// floating-point expansions (expansion sum and scale, sign of the most significant component). The
// answers are therefore exact, not "robust up to epsilon".
#pragma once

#include <cstdint>

namespace spherechain::runtime {

/// True when the two closed triangles (p1, q1, r1) and (p2, q2, r2) share at least one point:
/// crossing, touching at a point, along an edge, or overlapping when coplanar all count.
///
/// Parameters: each argument is one vertex, 3 floats (x, y, z) [Units: any, the same for all six]
/// [Space: any, the same for all six]; vertex order (winding) does not matter. Not nullable.
///
/// Same answer as CGAL's `CGAL::do_intersect(Triangle_3, Triangle_3)` with an exact-predicates kernel
/// on the same coordinates (converted to double), EXCEPT the convention: if either triangle is
/// degenerate (exactly zero area: collinear or coincident vertices, see TriangleIsDegenerate) the
/// answer is false — degenerate triangles never make contacts (CGAL would test the segment or point).
/// Any non-finite coordinate (NaN, ±Inf) gives false.
///
/// Exactness: exact for every finite float input — every difference of coordinates, product and sum
/// behind a sign is either certified by the error bound or recomputed exactly; no tolerance, no
/// overflow or underflow is possible from float inputs (|determinants| ≤ ~1e117, non-zero ones ≥ 2^-447).
/// The limit is the input itself: floats are taken as given (rounding done by the caller, e.g. skinning,
/// is not undone).
///
/// Cost (x86-64, -O2, one core of a 2-core cloud Xeon): ~15 ns when triangle 1 lies strictly on one side
/// of triangle 2's plane (3 filtered orientations), ~60 ns on average over box-overlapping neighbours,
/// ~95 ns for intersecting pairs (8 filtered orientations) — CGAL EPICK do_intersect: 25 / 120 / 145 ns
/// on the same pairs. The exact fallback runs only where the filter cannot certify a sign (touching,
/// coplanar, shared vertices, 1-ulp configurations): ~30 ns per orientation when plain double arithmetic
/// happens to be error-free (coarse coordinates), ~300 ns when it needs expansions; a coplanar pair on
/// integer coordinates ~270 ns. No allocation (≤ ~7 KB of stack in the expansion stage), no exceptions,
/// no global state: thread-safe, reentrant.
/// Source: Guigue & Devillers 2003 §3 (3D test), coplanar case by projection onto the axis plane of the
/// largest normal component and a 2D separating-edge test with exact orient2d; Shewchuk 1997 §4.
bool TrianglesIntersect(const float p1[3], const float q1[3], const float r1[3], const float p2[3], const float q2[3],
                        const float r2[3]);

/// True when the triangle (p, q, r) has exactly zero area: its three vertices are collinear or two
/// coincide (the three components of (q − p) × (r − p) are exactly zero). Same answer as CGAL's
/// `Triangle_3::is_degenerate()` with an exact-predicates kernel.
///
/// Parameters: 3 floats (x, y, z) each [Units: any] [Space: any]. Not nullable.
/// Non-finite coordinates (NaN, ±Inf) give false (not a zero-area triangle; TrianglesIntersect
/// rejects them anyway).
/// Exactness and sources as TrianglesIntersect (three exact orient2d, Shewchuk 1997 filter first).
/// Cost: a few ns when the filter certifies a non-zero component (every triangle that is not a sliver);
/// no allocation, thread-safe.
bool TriangleIsDegenerate(const float p[3], const float q[3], const float r[3]);

/// A triangle prepared once for many exact tests against others (the narrow phase meets most triangles
/// in several tests a frame): its vertices by coordinate and its plane in float with the error terms of
/// a semi-static filter (see TrianglesIntersect(const PreparedTriangle&, const PreparedTriangle&)). POD,
/// 64 bytes (one cache line); written by PrepareTriangle only. The float plane is a filter's input,
/// never an answer: every decision stays exact.
struct alignas(64) PreparedTriangle {
  float x[4], y[4], z[4];  ///< p, q, r by coordinate; lane 3: the filter's G (x), A (y) and M (z)
  float plane[4];          ///< n_f = fl((q − p) × (r − p)) (x, y, z) and δ_f = fl(n_f · p), in float
};
static_assert(sizeof(PreparedTriangle) == 64);

/// Prepares the triangle (p, q, r) for TrianglesIntersect(const PreparedTriangle&, const PreparedTriangle&).
/// Returns true when it can intersect something: every coordinate finite and the triangle not degenerate
/// (exactly as !TriangleIsDegenerate: a float normal component beyond its error bound certifies a non-zero
/// area, else the exact test decides). On false `*out` is written but must not be tested (degenerate or
/// non-finite triangles never intersect: the answer is false without a test).
/// Parameters: 3 floats (x, y, z) each [Units: any] [Space: any]; `out` not nullable.
/// Cost: ~20 ns (a float normal and its bounds; exact orient2d only for slivers); no allocation,
/// thread-safe.
bool PrepareTriangle(const float p[3], const float q[3], const float r[3], PreparedTriangle* out);

/// TrianglesIntersect on two prepared triangles, each prepared by PrepareTriangle with the answer true:
/// the same answer as TrianglesIntersect on the floats they were prepared from (exact; either argument
/// order). First a semi-static float filter, four lanes: a's vertices x against b's float plane,
/// n_f · x − δ_f, certified strictly on one side when beyond G_b · M_a + A_b (M_a: a's largest
/// |coordinate|), then b's against a's; the bound covers the float normal's and offset's distance to the
/// exact ones and every rounding (and underflow) of the float evaluation, for any float vertex under
/// gradual underflow, the IEEE default (with flush-to-zero, coordinates below ~2^-101 in magnitude are
/// the exception; the derivation is in triangle_intersect.cpp). Triangles with a coordinate beyond 2^40 get an infinite
/// bound. When the filter places every vertex strictly on a side of the other plane but neither triangle
/// all on one side, Guigue–Devillers' canonical form follows from those signs and its two interval
/// orientations are float-filtered too (Shewchuk's orient3d bound for float, exact where it is unsure);
/// any vertex the filter cannot place sends the pair to TrianglesIntersect's double filters and exact
/// evaluation. Cost (same machine as TrianglesIntersect's figures, MakeHuman neighbours): ~8 ns when the
/// float filter separates the planes (~70 % of box-overlapping pairs), ~40 ns for crossing planes
/// (TrianglesIntersect: ~130 ns on those), else about TrianglesIntersect's; no allocation, thread-safe.
bool TrianglesIntersect(const PreparedTriangle& a, const PreparedTriangle& b);

namespace detail {

/// Test and diagnostics hook: exactly TrianglesIntersect, and adds to `*exact_evaluations` (not
/// nullable) the number of orientation determinants whose sign the floating-point filter could not
/// certify and that were therefore evaluated exactly (error-free double stage or expansions). Same cost
/// as TrianglesIntersect plus a counter increment per exact evaluation; for tests and measurements.
bool TrianglesIntersectCounted(const float p1[3], const float q1[3], const float r1[3], const float p2[3],
                               const float q2[3], const float r2[3], uint64_t* exact_evaluations);

/// The same hook for prepared triangles: exactly TrianglesIntersect(a, b), adding to `*exact_evaluations`
/// (not nullable) the orientations that needed the exact evaluation.
bool TrianglesIntersectCounted(const PreparedTriangle& a, const PreparedTriangle& b, uint64_t* exact_evaluations);

/// The float filter of TrianglesIntersect(const PreparedTriangle&, const PreparedTriangle&) alone, for
/// tests: +1 when it certifies the three vertices of `t` strictly above the plane of `plane_of` (exact
/// orient3d(plane_of's p, q, r, vertex) > 0), −1 strictly below, 0 when it cannot tell. Both prepared
/// with PrepareTriangle returning true.
int FloatPlaneSide(const PreparedTriangle& t, const PreparedTriangle& plane_of);

/// The float orientation filter of the prepared path's interval test alone, for tests: +1 / −1 when it
/// certifies the sign of ((b − a) × (c − a)) · (d − a) (CGAL::orientation(a, b, c, d)), 0 when it cannot
/// tell or a |coordinate| is beyond 2^40 (outside the filter's range).
int FloatOrientation(const float a[3], const float b[3], const float c[3], const float d[3]);

/// The exact orientation the triangle test falls back on, for tests: the sign of ((b − a) × (c − a)) · (d − a)
/// for finite coordinates, and in `*stage` (opt) the stage that decided it: 0 the error-free double
/// evaluation, 1 the determinant of the rounded differences (Shewchuk 1997 §4.3, stage B), 2 its tail
/// correction (stage C), 3 the full expansions. 50 ns to 1 µs.
int ExactOrientation(const float a[3], const float b[3], const float c[3], const float d[3], int* stage);

/// Stage 3 of ExactOrientation alone (the full expansions, exact for finite coordinates), for tests.
int ExpansionOrientation(const float a[3], const float b[3], const float c[3], const float d[3]);

}  // namespace detail

}  // namespace spherechain::runtime
