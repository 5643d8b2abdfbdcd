#pragma once
// Y = T X for a block of K display patterns at once: one pass over T instead of K.
//
// Layouts (indices as in docs/conventions.md: row k = camera pixel, column l = display pixel):
//   X, dense   X[l * K + j] is pattern j's value at display pixel l ("pixel-major": the K values
//              one nonzero of T multiplies are adjacent, so each nonzero reads one contiguous run
//              of X, and a row's K sums sit in one small accumulator that stays in L1);
//   X, binary  bit j % 64 of bits[l * words + j / 64] says pattern j is 1 (else 0) at l,
//              words = ceil(K / 64): 64 patterns of a pixel in one word, only the lit ones summed;
//   Y          Y[k * K + j] = (T x_j)[k], camera-pixel-major, rows x K doubles.
//
// Arithmetic: Y[k, j] is the sum over row k's nonzeros i, in T's column order, of
// double(T.data[i]) * double(x_j[l_i]), accumulated in double: exactly the operations and the
// order of CsrMatrix::multiply (io/CsrMatrix.h), so every column of Y is bit for bit what
// apply_pattern (features/Features.h) gives for that pattern alone. The binary form skips the
// zeros; adding the products v * 0 = +-0 to a double sum that starts at +0 never changes it, so
// it equals the dense form with 0/1 values bit for bit.
//
// Parallel over T's rows (TBB, fixed blocks of rows, `threads` threads, 0: all cores): each row's
// K sums are made by one task alone, so Y is bit-identical whatever the thread count.
//
// Used by `ltmsim features --pattern` (several patterns, or a stack) and by acquire/'s simulated
// acquisition (acquire/Acquisition.h), which adds the sensor's noise to Y.
#include <cstdint>
#include <vector>

#include "io/CsrMatrix.h"

namespace ltm {

// Dense blocks of float or double values. Throws std::invalid_argument unless T is valid
// (CsrMatrix::check), K >= 1 and X has T.cols * K values.
std::vector<double> multiply_block(const CsrMatrix& T, const std::vector<float>& X, int K, int threads);
std::vector<double> multiply_block(const CsrMatrix& T, const std::vector<double>& X, int K, int threads);

// A bit-packed block of K 0/1 patterns (see above). Throws std::invalid_argument unless T is
// valid, K >= 1, words = ceil(K / 64) and bits has T.cols * words words.
std::vector<double> multiply_block_binary(const CsrMatrix& T, const std::vector<std::uint64_t>& bits, int words,
                                          int K, int threads);

}  // namespace ltm
