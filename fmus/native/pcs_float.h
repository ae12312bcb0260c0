/*
 * The floating-point rules the native models' numbers rely on, checked by the compiler: no
 * fused multiply-add (a contraction changes the last bits; clang and GCC's GNU modes
 * contract by default) and every double operation rounded to double (FLT_EVAL_METHOD 0; a
 * 32-bit x86 build with the x87 unit keeps 80-bit intermediates). With them a rebuild on any
 * platform gives the numbers of the shipped binaries bit for bit.
 */
#ifndef PCS_FLOAT_H
#define PCS_FLOAT_H

#include <float.h>

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#elif defined(__GNUC__) && !defined(__STRICT_ANSI__) && !defined(PCS_FP_CONTRACT_OFF)
#error "compile with -std=c99 (GCC's GNU modes fuse multiply-adds), or with -ffp-contract=off -DPCS_FP_CONTRACT_OFF"
#endif

#if !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#error "doubles must be evaluated in double precision (FLT_EVAL_METHOD 0): on 32-bit x86 compile with -msse2 -mfpmath=sse"
#endif

#endif
