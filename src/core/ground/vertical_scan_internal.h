// The vertical scan core's private header: what its stage files share (the function
// multiversioning of the hot paths, the SIMD headers, the model's constants, the ground line
// lookup that several stages inline).
#pragma once

#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>  // the AVX2 median (target attribute; called only on an AVX2 CPU)
#endif

#include "ladar_perception/ground/vertical_scan.h"

// The per-point and per-bin functions are compiled twice, for the x86-64 baseline (SSE2) and
// for x86-64-v3 (AVX2), and the loader picks the second on a CPU that has it (GCC function
// multiversioning, an ifunc per function). The source is the same: the SSE2 intrinsics get
// the three-operand VEX encoding (no register copies) and the compiler may vectorise scalar
// loops 8 wide. x86-64-v3 has FMA: CMakeLists.txt compiles this file with -ffp-contract=off,
// so no multiply-add is fused and both clones compute the same floats (the labels and
// P(obstacle) are bit-identical; see DEVELOPERS.md).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(LADAR_NO_CLONES)
#define LADAR_CLONES 1
#define LADAR_HOT_PATH __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define LADAR_HOT_PATH
#endif

#if defined(LADAR_CLONES)
// Whether this CPU runs AVX2: the stages' 8-lane loops (target attribute) run only where it does.
inline bool cpuHasAvx2() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return has;
}
#endif

// GCC's attribute on lambdas (clang rejects it after `mutable`, and inlines these lambdas
// without it).
#if defined(__GNUC__) && !defined(__clang__)
#define LADAR_ALWAYS_INLINE __attribute__((always_inline))
#else
#define LADAR_ALWAYS_INLINE
#endif

namespace ladar_perception {

constexpr float kPi = 3.14159265358979f;
constexpr int kMaxRingRows = 128;   // rows of the bin grid when the cloud carries `ring`
constexpr uint32_t kNoCell = 0xFFFFFFFFu;  // laser_neighbours: the cell of an unknown return
constexpr float kMinR = 0.05f;      // horizontal distance floor for Height / r [m]
constexpr int kAtanCells = 2048;    // atan LUT cells on [0, 1]: < 0.015 deg error
// Bins of at most this many returns take their median by rank (vertical_scan_column.cpp); the
// binning leaves this many readable floats past the last bin for it.
constexpr int kMaxRankBin = 32;

// The ground line of column col at r (inlined into the stages that read it per return).
inline float VerticalScanGround::groundLineHeight(int col, float r) const {
  vertical_scan::GroundLine line{&knot_height_[kKnotPad + static_cast<std::size_t>(col) * knot_stride_], knots_used_,
                                 inv_segment_};
  return line.heightAt(r);
}

}  // namespace ladar_perception
