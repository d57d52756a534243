// spherechain runtime SDK — umbrella header. Link spherechain::runtime.
//
//   AssetView view;  Status s = LoadAsset(bytes, size, &view);          // once, zero-copy
//   Context ctx;     s = ctx.Init(view);                                 // once, allocates
//   RefitJob refit;  refit.context = &ctx; refit.positions = {vb, nv, stride};
//   DetectJob det;   det.context = &ctx; det.output = buf; det.capacity = DetectBound(view, kM1);
//   det.count = &n;  // every frame: s = refit.Run(); s = det.Run();
#pragma once

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/context.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/refit.h"
#include "spherechain/runtime/status.h"
