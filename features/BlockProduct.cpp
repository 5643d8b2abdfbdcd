#include "features/BlockProduct.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace ltm {

namespace {

// Rows per task: enough that scheduling costs nothing against a row's nonzeros, few enough that
// the rows of a small T still spread over the threads. Fixed, so the partition into tasks never
// depends on the thread count (it would not matter anyway: each row is summed by one task).
constexpr std::int64_t kRowGrain = 16;

void check_block(const CsrMatrix& T, int K, std::size_t have, std::size_t per_pixel, const char* what) {
    const std::string problem = T.check();
    if (!problem.empty()) throw std::invalid_argument(std::string(what) + ": T is not a valid CSR matrix: " + problem);
    if (K < 1) throw std::invalid_argument(std::string(what) + ": a block needs at least one pattern (K = " + std::to_string(K) + ")");
    const std::size_t need = static_cast<std::size_t>(T.cols) * per_pixel;
    if (have != need)
        throw std::invalid_argument(std::string(what) + ": the block has " + std::to_string(have) + " values, but T's " +
                                    std::to_string(T.cols) + " display pixels need " + std::to_string(need));
}

// The one loop over T: row k's nonzeros in column order, each handed to add(l, v, acc) with the
// row's K accumulators (zeroed per row), which are then copied to Y's row k.
template <class Add>
std::vector<double> block_product(const CsrMatrix& T, int K, int threads, const Add& add) {
    const auto Ks = static_cast<std::size_t>(K);
    std::vector<double> Y(static_cast<std::size_t>(T.rows) * Ks);
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, T.rows, kRowGrain),
                          [&](const tbb::blocked_range<std::int64_t>& r) {
                              std::vector<double> acc(Ks);
                              for (std::int64_t k = r.begin(); k != r.end(); ++k) {
                                  std::fill(acc.begin(), acc.end(), 0.0);
                                  const auto e = static_cast<std::size_t>(T.indptr[static_cast<std::size_t>(k) + 1]);
                                  for (auto i = static_cast<std::size_t>(T.indptr[static_cast<std::size_t>(k)]); i < e; ++i)
                                      add(static_cast<std::size_t>(T.indices[i]), static_cast<double>(T.data[i]), acc.data());
                                  std::copy(acc.begin(), acc.end(), Y.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(k) * Ks));
                              }
                          },
                          tbb::simple_partitioner());
    });
    return Y;
}

template <class V>
std::vector<double> multiply_dense(const CsrMatrix& T, const std::vector<V>& X, int K, int threads) {
    check_block(T, K, X.size(), static_cast<std::size_t>(std::max(K, 0)), "multiply_block");
    const auto Ks = static_cast<std::size_t>(K);
    const V* x = X.data();
    return block_product(T, K, threads, [x, Ks](std::size_t l, double v, double* acc) {
        const V* xl = x + l * Ks;
        for (std::size_t j = 0; j < Ks; ++j) acc[j] += v * static_cast<double>(xl[j]);
    });
}

}  // namespace

std::vector<double> multiply_block(const CsrMatrix& T, const std::vector<float>& X, int K, int threads) {
    return multiply_dense(T, X, K, threads);
}

std::vector<double> multiply_block(const CsrMatrix& T, const std::vector<double>& X, int K, int threads) {
    return multiply_dense(T, X, K, threads);
}

std::vector<double> multiply_block_binary(const CsrMatrix& T, const std::vector<std::uint64_t>& bits, int words,
                                          int K, int threads) {
    if (K >= 1 && words != (K + 63) / 64)
        throw std::invalid_argument("multiply_block_binary: " + std::to_string(K) + " patterns need words = " +
                                    std::to_string((K + 63) / 64) + " per display pixel, not " + std::to_string(words));
    check_block(T, K, bits.size(), static_cast<std::size_t>(std::max(words, 0)), "multiply_block_binary");
    const auto W = static_cast<std::size_t>(words);
    const std::uint64_t* b = bits.data();
    // Bits past pattern K - 1 in the last word are ignored (they would address no accumulator).
    const std::uint64_t tail = K % 64 == 0 ? ~std::uint64_t(0) : (std::uint64_t(1) << (K % 64)) - 1;
    return block_product(T, K, threads, [b, W, tail](std::size_t l, double v, double* acc) {
        const std::uint64_t* w = b + l * W;
        for (std::size_t word = 0; word < W; ++word)
            for (std::uint64_t m = word + 1 == W ? w[word] & tail : w[word]; m; m &= m - 1)
                acc[word * 64 + static_cast<std::size_t>(__builtin_ctzll(m))] += v;
    });
}

}  // namespace ltm
