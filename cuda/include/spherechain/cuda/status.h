// spherechain cuda — status codes: the runtime's values plus CUDA failures.
#pragma once

#include <cstdint>

#include <cuda_runtime_api.h>

#include "spherechain/runtime/status.h"

namespace spherechain::cuda {

/// Outcome of every fallible spherechain::cuda call. Same layout and, for shared meanings, the same
/// numeric values as runtime::Status (bit 31 = failure; successes carry detail bits), so
/// `FromRuntime()` is a cast. CUDA-specific failures live in 0x8000'03xx. `[[nodiscard]]`.
enum class [[nodiscard]] Status : uint32_t {
  kOk = 0x0000'0000u,           ///< Success, outputs complete.
  kOkTruncated = 0x0000'0001u,  ///< Success, but more pairs overlapped than the output capacity
                                ///< (the device overflow flag was set); see Batch::Download.

  kErrorNullArgument = 0x8000'0001u,  ///< A required pointer was null / a required span empty.
  kErrorAlignment = 0x8000'0002u,     ///< Positions pointer not 4-byte aligned.
  kErrorInvalidJob = 0x8000'0003u,    ///< Arguments inconsistent (unknown mode/method/strategy, batch
                                      ///< not initialised, strategy not valid for the method, asset slot
                                      ///< out of range, too many instances).
  kErrorVertexCount = 0x8000'0004u,   ///< Instance::vertex_count != the asset's fingerprint.vertex_count.
  kErrorStride = 0x8000'0005u,        ///< Instance::stride_bytes < 12 or not a multiple of 4.
  kErrorOutOfMemory = 0x8000'0006u,   ///< Host or device allocation failed (setup calls only).
  kErrorJointCount = 0x8000'0008u,    ///< Instance::joint_count != the asset's Asset.joint_count.
  kErrorMissingField = 0x8000'0201u,  ///< Instance::joint_matrices set on an asset without joint weights
                                      ///< (baked from a mesh without a skin, or schema v1/v2: re-bake).

  kErrorCuda = 0x8000'0301u,      ///< A CUDA runtime call failed; LastCudaError() / LastCudaErrorString()
                                  ///< give the cudaError_t of this thread's last failure.
  kErrorNoDevice = 0x8000'0302u,  ///< No CUDA device (cudaGetDeviceCount failed or returned 0).
};

/// True for kOk and kOkTruncated. Cost: one compare.
constexpr bool Succeeded(Status s) { return (static_cast<uint32_t>(s) & 0x8000'0000u) == 0; }
/// True for every kError*.
constexpr bool Failed(Status s) { return !Succeeded(s); }

/// Maps a runtime status (same numeric value for shared meanings; others pass through unchanged and
/// print through runtime::ToString).
constexpr Status FromRuntime(runtime::Status s) { return static_cast<Status>(static_cast<uint32_t>(s)); }

/// Static, NUL-terminated English name of `s` (CUDA values here, others via runtime::ToString).
/// Never null. Lifetime: static.
const char* ToString(Status s);

/// The cudaError_t of the last CUDA failure that made a spherechain::cuda call on this thread return
/// kErrorCuda (cudaSuccess if none). Thread-local; not reset by successful calls.
cudaError_t LastCudaError();
/// cudaGetErrorString(LastCudaError()). Never null, static lifetime.
const char* LastCudaErrorString();

/// kOk when a CUDA device is usable (cudaGetDeviceCount succeeds with >= 1 device), else
/// kErrorNoDevice (the driver's error is kept in LastCudaError()). Cost: first call initialises the
/// CUDA runtime (milliseconds); thread-safe.
Status DeviceAvailable();

}  // namespace spherechain::cuda
