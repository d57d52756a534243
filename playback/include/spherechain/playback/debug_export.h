// spherechain playback — pictures of a bake for people: a glTF scene (mesh coloured by region + the
// spheres) viewable in any glTF viewer, and front/side PNG views rendered from SVG by rsvg-convert.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "spherechain/playback/types.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::playback {

/// sRGB colour of a region in every picture: R0 orange, R1 blue, R2 green, R3 purple, R4 grey.
std::array<float, 3> RegionColor(Region r);
/// Colour of region `region` of asset `a`: the paper's five as RegionColor(Region); a creature's
/// (Asset.regions, schema v4): the trunk grey, the limbs from a palette of 12 in region order (R0 orange,
/// R1 blue, R2 green, R3 purple as the paper's, then teal, brown, pink, olive, navy, cyan, lime, slate; no
/// red, amber or magenta, the colours of contacts).
std::array<float, 3> RegionColor(const runtime::AssetView& a, uint32_t region);
/// "R0 left arm (orange)  R1 right arm (blue) …" — the legend of RegionColor(a, ·), names from the asset.
std::string RegionLegend(const runtime::AssetView& a);

/// True when `path` ends in ".glb" (any case): the debug exporters then write binary glTF (GLB, the buffer
/// in its BIN chunk), else glTF JSON with the buffers embedded as data URIs.
bool GltfBinary(const std::string& path);

/// Writes `out_path` (.gltf with buffers embedded, or .glb: GltfBinary): node "mesh" = the character coloured by region
/// (COLOR_0 per vertex, from the asset's triangle_regions), node "spheres" = one UV sphere per asset
/// sphere (bind pose, region colour, 35 % opaque). `mesh` must match the asset's fingerprint counts.
/// Written atomically. Errors: kConfig (counts differ), kIo.
Status ExportDebugGltf(const Mesh& mesh, const runtime::AssetView& asset, const std::string& out_path);

/// Renders a 4-panel picture — front: regions | spheres; side: regions | spheres — as SVG text.
/// Orthographic, painter's algorithm, Lambert shading. `width_px` is the whole picture's width.
std::string RenderDebugSvg(const Mesh& mesh, const runtime::AssetView& asset, int width_px = 1600);

/// A sphere drawn in a frame picture: centre (model space, source units), radius, sRGB colour, opacity.
struct FrameSphere {
  std::array<float, 3> center;
  float radius = 0;
  std::array<float, 3> color{0.5f, 0.5f, 0.5f};
  float opacity = 0.35f;
};

/// One animation frame as a 4-panel SVG (front and side; each: mesh coloured by region with marked
/// triangles, then the mesh in grey with marked triangles and `spheres`). `positions`: the deformed
/// mesh, \#V×3 (model space). `triangle_marks`: \#T entries (shorter = unmarked), 0 none, 1 red (e.g. a
/// contact the proxy missed), 2 amber (a contact it found). `caption` is printed under the panels
/// (plain text, no markup). What `spherechain evaluate --png` shows.
std::string RenderFrameSvg(const Mesh& mesh, const runtime::AssetView& asset, const float* positions,
                           const std::vector<FrameSphere>& spheres, const std::vector<uint8_t>& triangle_marks,
                           const std::string& caption, int width_px = 1600);

/// `svg` rendered to PNG bytes by `rsvg-convert` (Debian librsvg2-bin), through its standard input and output:
/// no file is written (an interrupted caller leaves none, and the tool ends with it). `for_path` names the
/// picture in messages (may be empty). Errors: kIo "rsvg-convert is not installed …" when it cannot be started,
/// "rsvg-convert could not render the picture …" when it fails or writes nothing (its own message is on stderr).
Result<std::string> SvgToPngBytes(const std::string& svg, const std::string& for_path = {});

/// Writes `svg` to PNG (SvgToPngBytes), atomically (nothing is left at `png_path` on failure; with `keep_svg` the
/// SVG too, at `png_path` + ".svg"). Errors: SvgToPngBytes's, and kIo when a file cannot be written.
Status SvgToPng(const std::string& svg, const std::string& png_path, bool keep_svg = false);

/// Renders RenderDebugSvg to PNG with `rsvg-convert` (Debian librsvg2-bin). Errors: kIo when the tool
/// is missing or fails (the SVG is still written beside the PNG when `keep_svg`).
Status RenderDebugPng(const Mesh& mesh, const runtime::AssetView& asset, const std::string& png_path,
                      bool keep_svg = false);

/// "regions: R0 Tail, R1 HindLeg_L, …, R6 trunk (trunk)" for an asset that names its regions (a creature,
/// schema v4); empty for the paper's five (the tables' R0..R4 are documented).
std::string RegionLegendLine(const runtime::AssetView& view);
/// "R1-R2" for a region pair; with the asset's names for a creature: "R1-R2 (HindLeg_L-HindLeg_R)".
std::string RegionPairName(const runtime::AssetView& view, int a, int b);

/// `text` for XML and HTML (SVG text, attributes, JUnit): & < > " ' escaped, a newline as "&#10;", the
/// other control characters XML 1.0 forbids dropped (tab kept). Well-formed UTF-8 passes through unchanged;
/// each byte that does not start or continue a well-formed sequence (a name in another encoding, a cut
/// character) becomes U+FFFD, so the output is always well-formed UTF-8.
std::string XmlEscape(const std::string& text);

}  // namespace spherechain::playback
