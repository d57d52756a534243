// spherechain check --html: one self-contained page — the summary table, then per failing event its picture at
// the deepest frame (PNG through rsvg-convert, embedded) with a link into the viewer page of the clip.
#pragma once

#include <string>

#include "spherechain/evaluate/check.h"
#include "spherechain/import/types.h"
#include "spherechain/runtime/asset.h"

namespace spherechain::cli {

/// What the page names: the character and the asset files, and whether the clips played at their key times
/// (then the viewer's uniform frames are not the check's, and no frame links are written).
struct CheckPage {
  std::string character, asset_name;
  bool key_times = false;
  std::string rig;      ///< --rig, passed on to the viewer's command ("" none)
  bool baked = false;   ///< the asset was baked for this run and kept nowhere (--no-cache): the command bakes it
};

/// "1.23 cm (0.7 %)" when the report knows its units, else "0.0123 (0.7 %)": a depth and its share of the height.
std::string DepthText(double d, const evaluate::CheckReport& r);

/// The page for report `r` of `mesh` / `view` (CheckClips with `options`), into `*html` (the caller writes it).
/// False with `*error` when a frame cannot be skinned again or a picture cannot be rendered (rsvg-convert).
bool MakeCheckHtml(const CheckPage& page, const runtime::AssetView& view, const import::Mesh& mesh,
                   const evaluate::CheckOptions& options, const evaluate::CheckReport& r, std::string* html,
                   std::string* error);

}  // namespace spherechain::cli
