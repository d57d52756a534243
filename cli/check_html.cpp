// spherechain check --html: the self-contained report page (check_html.h).
#include "check_html.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "commands.h"
#include "html_embed.h"
#include "spherechain/import/file_io.h"
#include "spherechain/playback/debug_export.h"

namespace spherechain::cli {

namespace fs = std::filesystem;

// "1.23 cm (0.7 %)" with units, else "0.0123 (0.7 %)".
std::string DepthText(double d, const evaluate::CheckReport& r) {
  char b[64];
  if (r.unit_scale_m > 0) std::snprintf(b, sizeof b, "%.2f cm (%.2f %%)", d * r.unit_scale_m * 100.0, 100.0 * d / r.height);
  else std::snprintf(b, sizeof b, "%.4g (%.2f %%)", d, 100.0 * d / r.height);
  return b;
}

namespace {

// "1.234" (seconds, three decimals).
std::string Seconds(double t) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f", t);
  return b;
}

// "150.66 cm" with units, else "1.507 units".
std::string LengthText(double d, const evaluate::CheckReport& r) {
  char b[48];
  if (r.unit_scale_m > 0) std::snprintf(b, sizeof b, "%.2f cm", d * r.unit_scale_m * 100.0);
  else std::snprintf(b, sizeof b, "%.4g units", d);
  return b;
}

// `s` as one POSIX shell word: in single quotes, a quote inside as '\''; bare when only safe characters.
std::string ShellWord(const std::string& s) {
  const bool safe = !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || std::strchr("/._-+,:=@%", c);
  });
  if (safe) return s;
  std::string o = "'";
  for (const char c : s) o += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return o + "'";
}

// The command that writes a viewer page of `clip` (its frames are CheckClips' frames); with an asset baked
// for this run only, the bake first.
std::string ViewCommand(const CheckPage& a, const evaluate::CheckClip& clip, const std::vector<std::string>& poses) {
  const std::string rig = a.rig.empty() ? "" : " --rig " + ShellWord(a.rig);
  std::string cmd = a.baked ? "spherechain bake " + ShellWord(a.character) + rig + " -o check.sphc && spherechain view check.sphc"
                            : "spherechain view " + ShellWord(a.asset_name);
  cmd += " --mesh " + ShellWord(a.character) + rig;
  if (clip.morph) {
    cmd += " --morph";
    for (const std::string& p : poses) cmd += " " + ShellWord(p);
  } else {
    cmd += " --clip " + ShellWord(clip.name);
  }
  if (a.key_times) return cmd + " -o view.html  # (--key-times: the viewer's frames are uniform, not these)";
  return cmd + " --frames " + std::to_string(clip.frames) + " -o view.html";
}
}  // namespace

bool MakeCheckHtml(const CheckPage& a, const runtime::AssetView& view, const import::Mesh& mesh,
                   const evaluate::CheckOptions& options, const evaluate::CheckReport& r, std::string* page_out,
                   std::string* error) {
  const std::string& asset_name = a.asset_name;
  std::string page =
      "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>spherechain check: " + playback::XmlEscape(a.character) +
      "</title><style>body{font:14px system-ui,sans-serif;margin:24px;color:#222}table{border-collapse:collapse}"
      "td,th{padding:4px 10px;border-bottom:1px solid #ddd;text-align:left}.FAIL{color:#b00;font-weight:bold}"
      ".PASS{color:#070;font-weight:bold}figure{margin:16px 0 32px}img{max-width:100%;border:1px solid #ccc}"
      "code{background:#f4f4f4;padding:2px 4px}</style></head><body>\n";
  page += "<h1>spherechain check: " + playback::XmlEscape(fs::path(a.character).filename().string()) + "</h1>\n<p>" +
          playback::XmlEscape(a.character) + ", asset " + playback::XmlEscape(asset_name) + ". Height " + LengthText(r.height, r) +
          "; default threshold " + DepthText(r.max_depth, r) + ". " + (r.failed() ? "<span class=FAIL>FAIL</span>" : "<span class=PASS>PASS</span>") +
          "</p>\n<table><tr><th>clip</th><th>frames</th><th>events</th><th>failing</th><th>deepest</th><th>result</th></tr>\n";
  for (const evaluate::CheckClip& c : r.clips) {
    size_t failing = 0;
    for (const auto& e : c.events) failing += e.failed;
    page += "<tr><td>" + playback::XmlEscape(c.name) + "</td><td>" + std::to_string(c.frames) + "</td><td>" +
            std::to_string(c.events.size()) + "</td><td>" + std::to_string(failing) + "</td><td>" +
            DepthText(c.deepest(), r) + "</td><td class=" + (c.failed() ? "FAIL>FAIL" : "PASS>PASS") + "</td></tr>\n";
  }
  page += "</table>\n";
  std::vector<float> positions;
  for (const evaluate::CheckClip& c : r.clips) {
    if (!c.failed()) continue;
    page += "<h2>" + playback::XmlEscape(c.name) + "</h2>\n<p>Viewer of this clip: <code>" + playback::XmlEscape(ViewCommand(a, c, options.poses)) +
            "</code>, then open the links below.</p>\n";
    for (const evaluate::CheckEvent& e : c.events) {
      if (!e.failed) continue;
      if (auto s = evaluate::CheckFrame(mesh, options, c, e.deepest_frame, &positions); !s.ok())
        return *error = s.error().message, false;
      std::vector<uint8_t> marks(mesh.triangle_count(), 0);
      for (const auto& [ta, tb] : e.contacts) marks[ta] = marks[tb] = 1;
      const std::string caption = c.name + " frame " + std::to_string(e.deepest_frame) + " (" +
                                  Seconds(e.deepest_time) + " s): " + e.name + ", depth " + DepthText(e.depth, r);
      const std::string svg = playback::RenderFrameSvg(mesh, view, positions.data(), {}, marks, caption, 1200);
      auto png = playback::SvgToPngBytes(svg);
      if (!png.ok())
        return *error = "the picture of " + c.name + ": " + e.name + " at frame " + std::to_string(e.deepest_frame) +
                        ": " + png.error().message,
               false;
      const std::string& bytes = png.value();
      const std::string line = "frames " + std::to_string(e.first_frame) + "–" + std::to_string(e.last_frame) + " (" +
                               Seconds(e.first_time) + "–" + Seconds(e.last_time) + " s), deepest at frame " +
                               std::to_string(e.deepest_frame) + "; triangles " + std::to_string(e.triangles[0]) + " / " +
                               std::to_string(e.triangles[1]) + ", joints " + e.joints[0] + " / " + e.joints[1] + "; " +
                               std::to_string(e.contacts.size()) + " contacts there" +
                               (e.baseline.empty() ? "" : "; baseline: " + e.baseline);
      page += "<figure class=event><figcaption><b>" + playback::XmlEscape(e.name) + "</b> depth " + DepthText(e.depth, r) +
              " over " + DepthText(e.threshold, r) + ": " + playback::XmlEscape(line) + "." +
              (a.key_times ? std::string()
                           : " <a href=\"view.html#frame=" + std::to_string(e.deepest_frame) + "\">view at frame " +
                                 std::to_string(e.deepest_frame) + "</a>") +
              "</figcaption>\n<img alt=\"" + playback::XmlEscape(e.name) + " at frame " + std::to_string(e.deepest_frame) +
              "\" src=\"data:image/png;base64," + Base64(bytes.data(), bytes.size()) + "\"></figure>\n";
    }
    if (!c.fixed.empty()) {
      page += "<p>Fixed since the baseline:";
      for (const std::string& f : c.fixed) page += " " + playback::XmlEscape(f);
      page += "</p>\n";
    }
  }
  page += "</body></html>\n";
  *page_out = std::move(page);
  return true;
}


}  // namespace spherechain::cli
