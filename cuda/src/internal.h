// Private helpers of spherechain::cuda shared by its translation units.
#pragma once

#include <cuda_runtime_api.h>

#include "spherechain/cuda/status.h"

namespace spherechain::cuda::detail {

/// Records `e` as this thread's LastCudaError() and returns kErrorCuda (or kOk for cudaSuccess).
Status CudaStatus(cudaError_t e);

/// Device instance record (internal; built from Instance by Batch).
struct DeviceInstance {
  const char* positions;       // null when the instance has joint matrices only
  const float* joint_matrices; // null when it has positions only
  uint32_t stride_bytes;
  uint32_t asset;
  uint32_t sphere_offset;  // into Batch::spheres()
  uint32_t pad;
};
static_assert(sizeof(DeviceInstance) == 32);

}  // namespace spherechain::cuda::detail
