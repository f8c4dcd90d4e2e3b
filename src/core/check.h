// Invariant checks in debug builds (after pbrt-v4's DCHECK): NIMBUS_DCHECK(cond) prints file:line and
// the condition and aborts when cond is false. A failed check is a bug in nimbus, not bad input (bad
// input throws nimbus::Error), so aborting is right. With NDEBUG defined (Release builds) the macro
// expands to nothing that is evaluated: the condition is not computed, costs nothing and cannot change
// an image; it is still parsed (inside sizeof), so a check cannot rot unnoticed. NIMBUS_FORCE_DCHECKS
// turns the checks on in an optimised build: the sanitizer build (`make asan`, in CI) runs the fast
// suite with them.
#pragma once

#include <cstdio>
#include <cstdlib>

namespace nimbus::detail {

[[noreturn]] inline void dcheck_failed(const char* file, int line, const char* condition) {
  std::fprintf(stderr, "%s:%d: NIMBUS_DCHECK(%s) failed\n", file, line, condition);
  std::fflush(stderr);
  std::abort();
}

}  // namespace nimbus::detail

#if defined(NDEBUG) && !defined(NIMBUS_FORCE_DCHECKS)
#define NIMBUS_DCHECK(cond) static_cast<void>(sizeof(static_cast<bool>(cond)))
#define NIMBUS_DEBUG_CHECKS 0
#else
#define NIMBUS_DCHECK(cond) \
  ((cond) ? static_cast<void>(0) : ::nimbus::detail::dcheck_failed(__FILE__, __LINE__, #cond))
#define NIMBUS_DEBUG_CHECKS 1
#endif
