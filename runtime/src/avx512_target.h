// Private: compile the code between SPHERECHAIN_AVX512_BEGIN and SPHERECHAIN_AVX512_END for AVX-512 (F, VL,
// DQ, BW and POPCNT, the set kernels::Supported(Isa::kAvx512) checks), whatever the file's own -m flags, so
// that one binary holds a baseline and an AVX-512 copy and picks one per job. Use the pair at namespace scope,
// around whole functions or types; call what is between them only where kernels::Best() is kAvx512.
#pragma once

#ifdef __clang__
// _Pragma takes one string literal, so the clang line cannot be split.
#define SPHERECHAIN_AVX512_BEGIN \
  _Pragma("clang attribute push(__attribute__((target(\"avx512f,avx512vl,avx512dq,avx512bw,popcnt\"))), apply_to = function)")
#define SPHERECHAIN_AVX512_END _Pragma("clang attribute pop")
#else
// GCC 12's AVX-512 headers pass _mm512_undefined_ps() (a self-initialised variable) as the merge source of
// unmasked intrinsics, which -Wuninitialized reports at every inlined use (GCC bug 105593, fixed in 13);
// -Wpsabi notes that __m512 arguments pass differently with and without AVX-512 (these never cross the
// boundary: both sides of every call are compiled here).
#define SPHERECHAIN_AVX512_BEGIN                                 \
  _Pragma("GCC diagnostic push")                                 \
  _Pragma("GCC diagnostic ignored \"-Wuninitialized\"")          \
  _Pragma("GCC diagnostic ignored \"-Wmaybe-uninitialized\"")    \
  _Pragma("GCC diagnostic ignored \"-Wpsabi\"")                  \
  _Pragma("GCC push_options")                                    \
  _Pragma("GCC target(\"avx512f,avx512vl,avx512dq,avx512bw,popcnt\")")
#define SPHERECHAIN_AVX512_END \
  _Pragma("GCC pop_options")   \
  _Pragma("GCC diagnostic pop")
#endif
