// The playback library's own text helper (not installed): names from character files are bytes in whatever
// encoding the tool that wrote them used, and the outputs that carry them (glTF JSON, XML, HTML) must be UTF-8.
#pragma once

#include <string>

namespace spherechain::playback::detail {

/// `text` with each byte that does not start or continue a well-formed UTF-8 sequence (RFC 3629: no overlong
/// forms, no surrogates, nothing above U+10FFFF) replaced by U+FFFD; well-formed text unchanged. O(length).
std::string ValidUtf8(const std::string& text);

}  // namespace spherechain::playback::detail
