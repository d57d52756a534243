// spherechain baker — the shared vocabulary of the offline tools (spherechain/baker/types.h: Mesh, Skin,
// Clip, regions, Result / Error, Context) and the importers, named in the baker's namespace as well, so
// baker code and its callers say baker::Mesh or import::Mesh alike.
#pragma once

#include "spherechain/import/file_io.h"
#include "spherechain/import/import.h"
#include "spherechain/baker/types.h"
#include "spherechain/import/vertex_contract.h"

namespace spherechain::baker {
using namespace spherechain::import;  // NOLINT(google-build-using-namespace): one vocabulary, two rooms
}  // namespace spherechain::baker
