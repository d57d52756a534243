// Private: allocation-failure handling that compiles with and without exceptions.
#pragma once

#include <new>

// Init's allocation failures become kErrorOutOfMemory where exceptions exist; a runtime built with
// -fno-exceptions (the runtime-noexcept preset, as engines build) has no handler: an allocation
// failure then terminates, as std::vector's does there. Use: SPHERECHAIN_TRY { ... }
// SPHERECHAIN_CATCH_BAD_ALLOC { ... } (the handler becomes a dead else-branch).
#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
#define SPHERECHAIN_TRY try
#define SPHERECHAIN_CATCH_BAD_ALLOC catch (const std::bad_alloc&)
#else
#define SPHERECHAIN_TRY if (true)
#define SPHERECHAIN_CATCH_BAD_ALLOC else
#endif
