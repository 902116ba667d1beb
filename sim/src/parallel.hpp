// One parallel region per kernel, or none: with a single thread the body runs directly, and its orphaned
// `omp for` loops and barriers then bind to no team and cost nothing. (libgomp's team barrier issues a
// futex wake even in a team of one: six of them per step were a fifth of a one-thread run's time.)
#pragma once

#include <omp.h>

namespace pmfrag::detail {

template <class Body>
inline void parallel_region(Body&& body) {
  if (omp_get_max_threads() > 1) {
#pragma omp parallel
    body();
  } else {
    body();
  }
}

}  // namespace pmfrag::detail
