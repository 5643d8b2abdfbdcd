// features/BlockProduct.h: Y = T X for a block of patterns in one pass, against products written
// out by hand, against apply_pattern one pattern at a time (bit for bit), across thread counts,
// and the binary form against the dense one.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "features/BlockProduct.h"
#include "features/Features.h"
#include "io/CsrMatrix.h"
#include "tests/TestSupport.h"

using namespace ltm;

namespace {

// Rows given as (column, value) pairs in increasing column order.
CsrMatrix csr(std::int64_t cols, const std::vector<std::vector<std::pair<std::int32_t, float>>>& rows) {
    CsrMatrix T = CsrMatrix::zeros(static_cast<std::int64_t>(rows.size()), cols);
    for (std::size_t r = 0; r < rows.size(); ++r) {
        for (const auto& [l, v] : rows[r]) {
            T.indices.push_back(l);
            T.data.push_back(v);
        }
        T.indptr[r + 1] = static_cast<std::int64_t>(T.data.size());
    }
    EXPECT_EQ(T.check(), "");
    return T;
}

// A random T: each row holds each column with probability `density`, values of all magnitudes
// (so sums round, and any change of the summation order would show in the bits).
CsrMatrix random_csr(std::int64_t rows, std::int64_t cols, double density, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    CsrMatrix T = CsrMatrix::zeros(rows, cols);
    for (std::int64_t r = 0; r < rows; ++r) {
        for (std::int64_t l = 0; l < cols; ++l)
            if (u(rng) < density) {
                T.indices.push_back(static_cast<std::int32_t>(l));
                T.data.push_back(static_cast<float>(std::ldexp(u(rng), -static_cast<int>(20 * u(rng)))));
            }
        T.indptr[static_cast<std::size_t>(r) + 1] = static_cast<std::int64_t>(T.data.size());
    }
    return T;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

std::string error_of(const std::function<void()>& f) { return ltm::test::message_of<std::invalid_argument>(f); }

}  // namespace

// A 3 x 4 T with dyadic values (every product and sum below is exact in double), three patterns:
//   row 0 = [0.5, 0, 0.25, 0], row 1 = [], row 2 = [1, 2, 0, 4];
//   x0 = [1, 1, 1, 1]       -> y0 = [0.75, 0, 7]
//   x1 = [0, 1, 0, 1]       -> y1 = [0, 0, 6]
//   x2 = [0.5, -1, 2, 0.25] -> y2 = [0.25 + 0.5, 0, 0.5 - 2 + 1] = [0.75, 0, -0.5]
TEST(BlockProduct, HandBuiltProducts) {
    const CsrMatrix T = csr(4, {{{0, 0.5f}, {2, 0.25f}}, {}, {{0, 1.f}, {1, 2.f}, {3, 4.f}}});
    const std::vector<float> x0 = {1, 1, 1, 1}, x1 = {0, 1, 0, 1}, x2 = {0.5f, -1, 2, 0.25f};
    std::vector<float> X(12);
    for (int l = 0; l < 4; ++l) {
        X[static_cast<std::size_t>(l) * 3 + 0] = x0[static_cast<std::size_t>(l)];
        X[static_cast<std::size_t>(l) * 3 + 1] = x1[static_cast<std::size_t>(l)];
        X[static_cast<std::size_t>(l) * 3 + 2] = x2[static_cast<std::size_t>(l)];
    }
    const std::vector<double> Y = multiply_block(T, X, 3, 1);
    EXPECT_EQ(Y, (std::vector<double>{0.75, 0, 0.75, 0, 0, 0, 7, 6, -0.5}));
    // x0 and x1 bit-packed: pattern 0 on everywhere, pattern 1 on at l = 1, 3.
    const std::vector<std::uint64_t> bits = {0b01, 0b11, 0b01, 0b11};
    EXPECT_EQ(multiply_block_binary(T, bits, 1, 2, 1), (std::vector<double>{0.75, 0, 0, 0, 7, 6}));
}

// Every column of the block is apply_pattern of that pattern alone, bit for bit, for blocks that
// do and do not fill a task's rows, with 1, 2 and 7 threads; the double form of the same values
// too. The binary form equals the dense one with 0/1 values, across the 64-pattern word boundary.
TEST(BlockProduct, ColumnsAreSingleProductsBitForBitWhateverTheThreads) {
    const CsrMatrix T = random_csr(157, 300, 0.2, 7);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0, 1);
    for (int K : {1, 3, 64, 65, 130}) {
        std::vector<float> X(static_cast<std::size_t>(T.cols) * static_cast<std::size_t>(K));
        for (float& v : X) v = u(rng);
        const std::vector<double> Y = multiply_block(T, X, K, 1);
        ASSERT_EQ(Y.size(), static_cast<std::size_t>(T.rows) * static_cast<std::size_t>(K));
        for (int j = 0; j < K; ++j) {
            std::vector<float> x(static_cast<std::size_t>(T.cols));
            for (std::int64_t l = 0; l < T.cols; ++l) x[static_cast<std::size_t>(l)] = X[static_cast<std::size_t>(l) * K + j];
            const std::vector<double> y = apply_pattern(T, x);
            std::vector<double> column(static_cast<std::size_t>(T.rows));
            for (std::int64_t k = 0; k < T.rows; ++k) column[static_cast<std::size_t>(k)] = Y[static_cast<std::size_t>(k) * K + j];
            ASSERT_TRUE(same_bits(column, y)) << "K " << K << " pattern " << j;
        }
        for (int threads : {2, 7}) EXPECT_TRUE(same_bits(multiply_block(T, X, K, threads), Y)) << K << " " << threads;
        EXPECT_TRUE(same_bits(multiply_block(T, std::vector<double>(X.begin(), X.end()), K, 2), Y)) << K;

        // 0/1 patterns: dense floats and bits.
        const int words = (K + 63) / 64;
        std::vector<std::uint64_t> bits(static_cast<std::size_t>(T.cols) * static_cast<std::size_t>(words));
        std::vector<float> B(X.size());
        for (std::int64_t l = 0; l < T.cols; ++l)
            for (int j = 0; j < K; ++j)
                if (u(rng) < 0.5f) {
                    B[static_cast<std::size_t>(l) * K + j] = 1;
                    bits[static_cast<std::size_t>(l) * words + j / 64] |= std::uint64_t(1) << (j % 64);
                }
        const std::vector<double> Yb = multiply_block(T, B, K, 1);
        for (int threads : {1, 3}) EXPECT_TRUE(same_bits(multiply_block_binary(T, bits, words, K, threads), Yb)) << K;
    }
}

TEST(BlockProduct, RefusesBadArguments) {
    const CsrMatrix T = csr(4, {{{0, 0.5f}}, {}});
    EXPECT_NE(error_of([&] { multiply_block(T, std::vector<float>(7), 2, 1); }).find("need 8"), std::string::npos);
    EXPECT_NE(error_of([&] { multiply_block(T, std::vector<float>(), 0, 1); }).find("at least one pattern"),
              std::string::npos);
    EXPECT_NE(error_of([&] { multiply_block_binary(T, std::vector<std::uint64_t>(8), 2, 3, 1); }).find("words = 1"),
              std::string::npos);
    CsrMatrix bad = T;
    bad.data[0] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(error_of([&] { multiply_block(bad, std::vector<float>(4), 1, 1); }).find("not a valid CSR matrix"),
              std::string::npos);
}
