// spherechain playback — the baker's types playback works on, named in this namespace: the imported
// character (Mesh with its Skin, Nodes and Clips) and Result<T> / Status / Error for fallible calls.
// Playback is offline code like the baker (it links spherechain::baker); a game links only the runtime.
#pragma once

#include "spherechain/baker/types.h"

namespace spherechain::playback {

using baker::Channel;
using baker::Clip;
using baker::Error;
using baker::MakeError;
using baker::Mesh;
using baker::Node;
using baker::Ok;
using baker::Result;
using baker::Skin;
using baker::SkinJoint;
using baker::Status;

}  // namespace spherechain::playback
