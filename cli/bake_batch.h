// spherechain bake A B ... --out-dir DIR [-j N]: several characters in one call, each baked on its own.
#pragma once

#include <string>
#include <vector>

#include "spherechain/baker/bake.h"

namespace spherechain::cli {

/// Bakes every input with `config` into DIR/<input stem>.sphc, `jobs` bakes at a time (worker threads, each
/// bake with its own Context; the baker's own parallel loops share the cores). Each asset is the same bytes
/// as `spherechain bake INPUT -o DIR/<stem>.sphc` with the same configuration writes, and is written
/// atomically as soon as its bake ends; a failed input writes nothing and stops nothing else.
/// Before any bake: two inputs with one stem (one output) are refused, naming both (exit 2), and `out_dir` is
/// created when missing. On stderr: a progress bar when stderr is a terminal, else one line per finished
/// input; each failure as `error: <kind>: <message>`; each bake's warnings, prefixed by its file name (its
/// info lines with -v). On stdout (not with -q): a summary table, one row per input. Returns 0 when every
/// input baked, 1 when one failed, 2 for a usage error.
int RunBatchBake(const std::vector<std::string>& inputs, const std::string& out_dir, unsigned jobs,
                 const baker::BakeConfig& config);

}  // namespace spherechain::cli
