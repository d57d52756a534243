// spherechain cuda SDK — umbrella header. Link spherechain::cuda (and spherechain::runtime).
//
//   cuda::DeviceAsset asset;  s = asset.Upload(view);                         // once per asset
//   cuda::Instance inst{d_positions, view.vertex_count, 12, /*asset=*/0};
//   const cuda::DeviceAsset* assets[] = {&asset};
//   cuda::Batch batch;        s = batch.Init(assets, 1, &inst, 1);              // once, allocates
//   s = batch.Run({RefitMode::kPivotFrame, DetectMethod::kM1}, stream);        // per frame, async
//   // batch.pairs() / batch.counters() on the device once the stream got there.
#pragma once

#include "spherechain/cuda/asset.h"
#include "spherechain/cuda/batch.h"
#include "spherechain/cuda/status.h"
