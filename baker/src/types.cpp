#include "spherechain/baker/types.h"

namespace spherechain::baker {

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
  switch (r) {
    case Region::kLeftArm: return "R0";
    case Region::kRightArm: return "R1";
    case Region::kLeftLeg: return "R2";
    case Region::kRightLeg: return "R3";
    case Region::kTorso: return "R4";
  }
  return "R?";
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

}  // namespace spherechain::baker
