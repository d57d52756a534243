// spherechain CLI — embedding a page, three.js and JSON data in one self-contained HTML file (`view`).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace spherechain::cli {

/// three.js files the viewer embeds, relative to the three package folder.
extern const char* const kThreeModule;
extern const char* const kOrbitControls;

/// The three.js package folder (holding kThreeModule and kOrbitControls), the first that has both of:
/// --three; the installed copy, <executable's folder>/SPHERECHAIN_BIN_TO_DATA/three (bin/ →
/// share/spherechain/); the source tree's viewer/node_modules/three (`npm ci` in viewer/). Empty when
/// none has them; `*looked` lists where it looked.
std::string FindThree(const std::string& explicit_dir, std::string* looked);
/// Reads a whole file as text; false when it cannot be opened.
bool ReadText(const std::filesystem::path& path, std::string* out);
/// Standard base64 (RFC 4648, padded) of `size` bytes.
std::string Base64(const void* data, size_t size);
template <class T>
std::string Base64(const std::vector<T>& v) {
  return Base64(v.data(), v.size() * sizeof(T));  // little endian: the hosts we build on (and the browsers)
}
/// JSON that may sit inside <script>: "</" and "<!--" cannot end or confuse the element.
std::string ScriptSafeJson(const nlohmann::json& j);
/// Replaces the one occurrence of `marker` in `*page`; false when it is not there.
bool ReplaceOnce(std::string* page, const std::string& marker, const std::string& with);

}  // namespace spherechain::cli
