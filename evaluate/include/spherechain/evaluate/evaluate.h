// spherechain evaluate — measures the proxy and the narrow phase against the exact truth, frame by frame,
// over an animation of the character an asset was baked from. What `spherechain evaluate` prints and
// writes, as a library call (the CLI, tests and tools use it alike).
//
// Every frame of the animation: the deformed mesh's exact self-intersections (ground truth: every
// intersecting pair of triangles that share no welded corner, CGAL box intersection + exact predicates,
// baker/contacts.h), the runtime's narrow phase on the same frame, and the proxy's sphere pairs (M1 chains,
// M2 all spheres) after the refit. A *contact* is an intersecting pair whose owning spheres (surrounding
// regions, paper §5.1) differ and are not an excluded pair; the other intersections (same sphere, excluded
// pair: skinning artefacts at joints) are counted apart. Since that truth follows the asset's exclusions and
// sphere ownership, a second one does not: the intersecting pairs whose triangles' bind-pose centroids lie at
// least `crease_rel` of the height apart (contacts by bind distance), and how many of them M2's sphere and
// region pairs cover.
//
// Reported (Evaluation::report, the JSON document; Evaluation::text, the table): the proxy's recall (region
// pairs and sphere pairs; per contact, the share the narrow phase finds when restricted to the proxy's sphere
// pairs — NarrowPhaseJob::sphere_pairs — and the share whose meeting point lies within the margin of both
// spheres of a reported pair of its regions), its false alarms (a region pair reported where no triangles of
// the two regions come within `margin_rel`), the sphere-pair precision (the share of M2's pairs whose own
// surrounding regions come within it), the narrow phase's recall and precision (triangle pairs), bind-pose
// coverage / protrusion of φ1, φ1', φ2 (baker/coverage.h), and per frame the refit spheres' coverage of the
// deformed mesh and how far they stick out of its skin. A margin sweep re-runs M1 and M2 on the same refit
// spheres with other contact margins (DetectJob::margin), each row with the region pairs the narrow phase
// behind M2's pairs finds contacts of (reach regions; one margin for every pair, an asset's fold margin set
// to it) and its time.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "spherechain/import/file_io.h"
#include "spherechain/import/types.h"
#include "spherechain/playback/animation_source.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::evaluate {

/// The contact margins a sweep tries by default, as fractions of the body height.
inline constexpr double kDefaultSweepMargins[] = {0.0, 0.001, 0.002, 0.003, 0.004, 0.005, 0.006, 0.008, 0.01, 0.015};

/// Parses a sweep specification into `*margins` (sorted, unique): "" → none, "auto" → kDefaultSweepMargins,
/// else comma-separated fractions of the body height in [0, 0.1]. Errors: kConfig "--sweep-margin: 'x' is
/// not a margin in [0, 0.1] (a fraction of the body height)".
import::Status ParseSweepMargins(const std::string& text, std::vector<double>* margins);

/// What to measure and how. Fractions are of the body height (the bind pose's extent along its up axis).
struct EvaluateOptions {
  std::string asset_name;  ///< the asset's file, for the report (JSON "asset", the table's first line)
  std::string mesh_name;   ///< the character's file, for the report (JSON "mesh")
  /// A reported region pair is a false alarm when no triangles of the two regions come within this
  /// [Limit: [0, 1)]. Also the sphere-pair precision's distance.
  double margin_rel = 0.01;
  /// The asset-independent truth's bind-centroid distance [Limit: [0, 1]]: nearer pairs are skin folding
  /// at a joint. Also the skin contacts' crease (geodesic, on the welded bind surface) when wider than the
  /// asset's: the definition's truth and its narrow-phase job are then both taken at this crease.
  double crease_rel = 0.03;
  /// "paper" or "frame" (RefitJob from the deformed vertices, RefitMode kPaper / kPivotFrame), or "joints"
  /// (JointRefitJob from the frame's skinning matrices; needs an asset with joint weights and a rigged mesh).
  std::string refit = "frame";
  /// Region pairs by the paper's five regions (an extended asset's hands count as arms, feet as legs, the
  /// head as the torso), comparable with a paper-layout asset; false: the asset's own regions. A creature
  /// asset has no paper regions: kConfig.
  bool paper_regions = false;
  /// Measure bind-pose coverage of φ1, φ1', φ2 and the refit spheres' coverage on every frame (the costly part).
  bool coverage = true;
  /// [opt] Contact margins to sweep (fractions of the height; ParseSweepMargins); empty: no sweep.
  std::vector<double> sweep_margins_rel;
  /// [opt] Writes a picture of the frame with the most missed contacts here (PNG through rsvg-convert):
  /// contact triangles red (missed by M2's sphere pairs) or amber (found), and the refit spheres.
  std::string png_path;
  /// [opt] Called after each frame with (frames done, frames, seconds since the start).
  std::function<void(uint32_t, uint32_t, double)> progress;
};

/// The measurements.
struct Evaluation {
  nlohmann::json report;  ///< what `evaluate --json` writes: per frame, the margin sweep, the summary
  std::string text;       ///< the human table `evaluate` prints (a header, one line per frame, the summary)
  double recall_m1 = 1.0;  ///< the proxy's region-pair recall, M1 (1 when there is nothing to find)
  double recall_m2 = 1.0;  ///< the same, M2
  int png_frame = -1;      ///< the frame pictured at EvaluateOptions::png_path, −1 when none was asked for
};

/// Plays `animation` over `mesh` (the character `asset` was baked from: playback::OpenCharacter checks that)
/// and measures every frame as the header says. Nothing is written unless every frame succeeded (only
/// `png_path`; the report is returned). Errors: kConfig (an option out of its limits, --refit joints on an
/// asset without joint weights or with another joint count), kFormat (the asset predates the narrow phase:
/// re-bake it), kInternal (a runtime job failed; the message names the job and its status), those of the
/// animation's frames, of the exact intersection and coverage measures (with the frame), and of the PNG
/// (kIo). `log` [opt] receives warnings (a frame with more than 2^20 narrow-phase contacts).
/// Cost: dominated by the exact ground truth (~0.1 s a frame on 27k triangles) and, with `coverage`, the
/// coverage measure; memory ~24 MB for two 2^20-contact buffers (the frame pipeline's and its own, 12 bytes a
/// contact) plus the mesh's size a few times.
import::Result<Evaluation> Evaluate(const runtime::AssetView& asset, const import::Mesh& mesh,
                                    const playback::Animation& animation, const EvaluateOptions& options,
                                    import::Context* log = nullptr);

}  // namespace spherechain::evaluate
