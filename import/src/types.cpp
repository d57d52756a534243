#include "spherechain/import/types.h"

#include <algorithm>
#include <filesystem>
#include <system_error>
#include <vector>

namespace spherechain::import {

void Context::RecordFileRead(const std::string& path) {
  if (path.empty()) return;
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p = fs::absolute(path, ec);
  std::string abs = ec ? path : p.lexically_normal().string();
  // A `..` after a symbolic link to a folder leads to the link target's parent, not back to where the path
  // came from: the path up to its last `..` is resolved as it is on disk, the rest kept as named. Dropping
  // `dir/..` by the text alone named files that do not exist (depfiles) and let an output overwrite a file
  // the bake had read (OutputsClash).
  if (!ec) {
    const std::vector<fs::path> parts(p.begin(), p.end());
    size_t last = parts.size();  // the last `..`
    for (size_t k = 0; k < parts.size(); ++k)
      if (parts[k] == "..") last = k;
    if (last < parts.size()) {
      fs::path upto, rest;
      for (size_t k = 0; k < parts.size(); ++k) (k <= last ? upto : rest) /= parts[k];
      const fs::path dir = fs::weakly_canonical(upto, ec);
      if (!ec) abs = (dir / rest).lexically_normal().string();
    }
  }
  if (std::find(files_read.begin(), files_read.end(), abs) == files_read.end()) files_read.push_back(abs);
}

const char* RegionName(Region r) {
  switch (r) {
    case Region::kLeftArm: return "left_arm";
    case Region::kRightArm: return "right_arm";
    case Region::kLeftLeg: return "left_leg";
    case Region::kRightLeg: return "right_leg";
    case Region::kTorso: return "torso";
  }
  return "none";
}

const char* RegionSymbol(Region r) {
  static const char* const kSymbols[kMaxRegions] = {
      "R0",  "R1",  "R2",  "R3",  "R4",  "R5",  "R6",  "R7",  "R8",  "R9",  "R10", "R11", "R12", "R13", "R14", "R15",
      "R16", "R17", "R18", "R19", "R20", "R21", "R22", "R23", "R24", "R25", "R26", "R27", "R28", "R29", "R30", "R31"};
  const int k = static_cast<int>(r);
  return k < kMaxRegions ? kSymbols[k] : "R?";
}

std::vector<RegionInfo> RegionLayout::PaperRegions() {
  std::vector<RegionInfo> r(5);
  const char* names[5] = {"left_arm", "right_arm", "left_leg", "right_leg", "torso"};
  const int mirrors[5] = {1, 0, 3, 2, -1};
  for (int k = 0; k < 5; ++k) {
    r[size_t(k)].name = names[k];
    r[size_t(k)].mirror = mirrors[k];
  }
  r[4].kind = RegionKind::kTrunk;
  return r;
}

const char* ToString(Error::Code code) {
  switch (code) {
    case Error::Code::kIo: return "io";
    case Error::Code::kFormat: return "format";
    case Error::Code::kInvalidMesh: return "invalid-mesh";
    case Error::Code::kSegmentation: return "segmentation";
    case Error::Code::kFit: return "fit";
    case Error::Code::kConfig: return "config";
    case Error::Code::kInternal: return "internal";
    case Error::Code::kImplausible: return "implausible";
  }
  return "unknown";
}

std::string ToString(const Error& error) { return std::string(ToString(error.code)) + ": " + error.message; }

}  // namespace spherechain::import
