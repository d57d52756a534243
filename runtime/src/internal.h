// Private: job kernels with access to Context's arrays (one definition, used by refit.cpp/detect.cpp).
#pragma once

#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/refit.h"

namespace spherechain::runtime {

struct Context::Internal {
  static void Refit(const RefitJob& job, uint32_t begin, uint32_t end);
  static void DetectChain(const Context& ctx, uint32_t chain);
  static Status DetectM1(const DetectJob& job);
  static Status DetectM2(const DetectJob& job);
};

}  // namespace spherechain::runtime
