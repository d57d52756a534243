// Paths to the real inputs the tests use, and the visible skip when they are absent.
#pragma once

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace spherechain::test {

inline std::string SharedData(const std::string& rel) { return std::string(SPHERECHAIN_SHARED_DATA_DIR) + "/" + rel; }
inline std::string AssimpModel(const std::string& rel) { return std::string(SPHERECHAIN_ASSIMP_MODELS_DIR) + "/" + rel; }
inline std::string SourceFile(const std::string& rel) { return std::string(SPHERECHAIN_SOURCE_DIR) + "/" + rel; }

/// Marks the running test case skipped: a doctest MESSAGE and a `SKIPPED: <why>` line on stdout, which the
/// suites' ctest entries match (SKIP_REGULAR_EXPRESSION "SKIPPED:"), so ctest reports the case as skipped,
/// never as passed. The caller returns right after; a test that printed this must not go on to check anything.
inline void Skip(const std::string& why) {
  MESSAGE("SKIPPED: " << why);
  std::printf("SKIPPED: %s\n", why.c_str());
  std::fflush(stdout);
}

/// True when `path` exists; otherwise marks the test case skipped (Skip) and returns false so the test
/// returns at once. Use: `if (!spherechain::test::Require(path)) return;`. For files that are part of the
/// repository use REQUIRE(std::filesystem::exists(path)) instead: their absence is a failure.
inline bool Require(const std::string& path) {
  if (std::filesystem::exists(path)) return true;
  Skip("required test input not found: " + path + " (../shared/data or Debian assimp-testmodels is absent)");
  return false;
}

/// For a test case that loops over several real inputs and checks those that are present: Found(path) says
/// whether to check this one; when the case ends without having found any, it is marked skipped (Skip).
/// Declare it before the loop: `SomeInputs inputs; for (...) { if (!inputs.Found(path)) continue; ... }`.
class SomeInputs {
 public:
  SomeInputs() = default;
  SomeInputs(const SomeInputs&) = delete;
  SomeInputs& operator=(const SomeInputs&) = delete;
  ~SomeInputs() {
    if (found_ == 0) Skip("none of this test's inputs was found (../shared/data or Debian assimp-testmodels is absent)");
  }
  bool Found(const std::string& path) {
    if (std::filesystem::exists(path)) return ++found_, true;
    MESSAGE("input not found, not checked: " << path);
    return false;
  }

 private:
  int found_ = 0;
};

}  // namespace spherechain::test
