// spherechain CLI — what `view` needs to embed a page and its data in one HTML file (html_embed.h).
#include "html_embed.h"

#include "commands.h"

#include <fstream>
#include <sstream>
#include <vector>

namespace spherechain::cli {

namespace fs = std::filesystem;

const char* const kThreeModule = "build/three.module.min.js";
const char* const kOrbitControls = "examples/jsm/controls/OrbitControls.js";

std::string FindThree(const std::string& explicit_dir, std::string* looked) {
  std::vector<fs::path> candidates;
  if (!explicit_dir.empty()) {
    candidates.push_back(explicit_dir);
  } else {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) candidates.push_back((exe.parent_path() / SPHERECHAIN_BIN_TO_DATA / "three").lexically_normal());
    candidates.push_back(fs::path(SPHERECHAIN_SOURCE_VIEWER_DIR) / "node_modules" / "three");
  }
  for (const fs::path& c : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(c / kThreeModule, ec) && fs::is_regular_file(c / kOrbitControls, ec)) return c.string();
    if (!looked->empty()) *looked += ", ";
    *looked += c.string();
  }
  return {};
}

bool ReadText(const fs::path& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  *out = s.str();
  return static_cast<bool>(in) || in.eof();
}

std::string Base64(const void* data, size_t size) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < size; i += 3) {
    const uint32_t v = (uint32_t(p[i]) << 16) | (uint32_t(p[i + 1]) << 8) | p[i + 2];
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < size) {
    const uint32_t v = (uint32_t(p[i]) << 16) | (i + 1 < size ? uint32_t(p[i + 1]) << 8 : 0u);
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}


std::string ScriptSafeJson(const nlohmann::json& j) {
  std::string s = JsonText(j, -1);
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '<') {
      out += "\\u003c";  // only inside strings: JSON has no '<' elsewhere
    } else {
      out += s[i];
    }
  }
  return out;
}

bool ReplaceOnce(std::string* page, const std::string& marker, const std::string& with) {
  const size_t at = page->find(marker);
  if (at == std::string::npos) return false;
  page->replace(at, marker.size(), with);
  return true;
}

}  // namespace spherechain::cli
