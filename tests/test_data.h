// Paths to the real inputs the tests use, and the visible skip when they are absent.
#pragma once

#include <doctest/doctest.h>

#include <filesystem>
#include <string>

namespace spherechain::test {

inline std::string SharedData(const std::string& rel) { return std::string(SPHERECHAIN_SHARED_DATA_DIR) + "/" + rel; }
inline std::string AssimpModel(const std::string& rel) { return std::string(SPHERECHAIN_ASSIMP_MODELS_DIR) + "/" + rel; }
inline std::string SourceFile(const std::string& rel) { return std::string(SPHERECHAIN_SOURCE_DIR) + "/" + rel; }

/// True when `path` exists; otherwise prints a visible SKIPPED message (doctest MESSAGE) and returns
/// false so the test returns early. Use: `if (!spherechain::test::Require(path)) return;`
inline bool Require(const std::string& path) {
  if (std::filesystem::exists(path)) return true;
  MESSAGE("SKIPPED: required test input not found: " << path
          << " (../shared/data or Debian assimp-testmodels is absent)");
  return false;
}

}  // namespace spherechain::test
