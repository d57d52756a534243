// spherechain::cuda status names and the thread's last CUDA error.
#include "spherechain/cuda/status.h"

#include "internal.h"

namespace spherechain::cuda {
namespace {
thread_local cudaError_t g_last_error = cudaSuccess;
}  // namespace

namespace detail {
Status CudaStatus(cudaError_t e) {
  if (e == cudaSuccess) return Status::kOk;
  g_last_error = e;
  return e == cudaErrorMemoryAllocation ? Status::kErrorOutOfMemory : Status::kErrorCuda;
}
}  // namespace detail

const char* ToString(Status s) {
  switch (s) {
    case Status::kErrorCuda: return "kErrorCuda: a CUDA runtime call failed (see LastCudaErrorString())";
    case Status::kErrorNoDevice: return "kErrorNoDevice: no CUDA device is available";
    case Status::kErrorOutOfMemory: return "kErrorOutOfMemory: host or device allocation failed";
    case Status::kOkTruncated: return "kOkTruncated: success, but more pairs overlapped than the output capacity";
    default: return runtime::ToString(static_cast<runtime::Status>(static_cast<uint32_t>(s)));
  }
}

cudaError_t LastCudaError() { return g_last_error; }
const char* LastCudaErrorString() { return cudaGetErrorString(g_last_error); }

Status DeviceAvailable() {
  int n = 0;
  const cudaError_t e = cudaGetDeviceCount(&n);
  if (e != cudaSuccess) {
    g_last_error = e;
    (void)cudaGetLastError();  // clear the sticky-free error so later calls are not confused
    return Status::kErrorNoDevice;
  }
  return n > 0 ? Status::kOk : Status::kErrorNoDevice;
}

}  // namespace spherechain::cuda
