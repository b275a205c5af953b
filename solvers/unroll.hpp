#pragma once
// LIEDYN_UNROLL before a loop with a compile-time trip count asks for full unrolling: GCC
// does not unroll the triangular loop nests of the small Cholesky kernels by itself, and
// unrolled they run ~2× faster. Internal to solvers/.

#if defined(__clang__)
#define LIEDYN_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define LIEDYN_UNROLL _Pragma("GCC unroll 16")
#else
#define LIEDYN_UNROLL
#endif
