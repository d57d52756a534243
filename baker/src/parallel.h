// spherechain baker — ParallelFor: the baker's one way to spread independent work over the cores.
#pragma once

#include <cstddef>

#if SPHERECHAIN_BAKER_TBB
#include <tbb/parallel_for.h>
#endif

namespace spherechain::baker::detail {

/// fn(i) for every i in [first, last): on all cores with TBB (baker/CMakeLists.txt links it when
/// found), one after another without. Each i must be independent of the others and write only what
/// is its own, so the result is the same on any number of cores (the bakes stay byte-identical).
template <class Fn>
void ParallelFor(size_t first, size_t last, Fn&& fn) {
#if SPHERECHAIN_BAKER_TBB
  if (first < last) tbb::parallel_for(first, last, fn);
#else
  for (size_t i = first; i < last; ++i) fn(i);
#endif
}

}  // namespace spherechain::baker::detail
