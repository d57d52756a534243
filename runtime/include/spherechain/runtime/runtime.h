// spherechain runtime SDK — umbrella header. Link spherechain::runtime.
//
//   AssetView view;  Status s = LoadAsset(bytes, size, &view);          // once, zero-copy
//   Model model;     s = model.Init(view);                               // once per asset, shared
//   Workspace ws;    s = ws.Init(model);                                 // once per character
//   RefitJob refit;  refit.model = &model; refit.workspace = &ws; refit.positions = {vb, nv, stride};
//   DetectJob det;   det.model = &model; det.workspace = &ws; det.output = buf;
//   det.capacity = DetectBound(view, kM1); det.count = &n;  // every frame: refit.Run(); det.Run();
//   BatchJob: refit + detect of many characters sharing one model (batch.h).
#pragma once

#include "spherechain/runtime/asset.h"
#include "spherechain/runtime/batch.h"
#include "spherechain/runtime/model.h"
#include "spherechain/runtime/detect.h"
#include "spherechain/runtime/narrow_phase.h"
#include "spherechain/runtime/refit.h"
#include "spherechain/runtime/status.h"
