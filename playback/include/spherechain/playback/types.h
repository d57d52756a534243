// spherechain playback — the imported character's types playback works on (spherechain/import), named in
// this namespace: Mesh with its Skin, Nodes and Clips, and Result<T> / Status / Error for fallible calls.
// Playback is offline code (it links spherechain::import, not the baker); a game links only the runtime.
#pragma once

#include "spherechain/import/types.h"

namespace spherechain::playback {

using import::Channel;
using import::Clip;
using import::Context;
using import::Error;
using import::MakeError;
using import::Mesh;
using import::Node;
using import::Ok;
using import::Region;
using import::RegionSymbol;
using import::Result;
using import::Skin;
using import::SkinJoint;
using import::UpAxis;
using import::Status;

}  // namespace spherechain::playback
