#pragma once
// The light transport matrix in compressed sparse row (CSR) form, the layout scipy.sparse.csr_matrix
// uses and the one `ltm.npz` stores (io/LtmFile.h).
//
// Row k is camera pixel k = m * N + n, column l is display pixel l = p * Q + q
// (docs: docs/conventions.md, "Pixel indices"). The nonzeros of row r are
// indices[indptr[r] .. indptr[r+1]) with their values in data[...] at the same positions; the
// columns of a row are strictly increasing (scipy's "canonical format": sorted, no duplicates).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ltm {

struct CsrMatrix {
    std::int64_t rows = 0, cols = 0;
    std::vector<std::int64_t> indptr;   // rows + 1 entries, indptr[0] = 0, indptr[rows] = nnz
    std::vector<std::int32_t> indices;  // column of each nonzero, strictly increasing within a row
    std::vector<float> data;            // value of each nonzero, finite

    std::size_t nnz() const { return data.size(); }

    // An all-zero rows x cols matrix (indptr = rows + 1 zeros).
    static CsrMatrix zeros(std::int64_t rows, std::int64_t cols);

    // Empty if the matrix is valid, else one sentence saying what is wrong (the first problem
    // found, with the offending position): rows, cols >= 0; indptr has rows + 1 entries, starts at
    // 0, never decreases and ends at nnz; indices and data have the same size; every index lies in
    // [0, cols) and the indices of each row strictly increase; every value is finite.
    std::string check() const;

    // y = T x: x has `cols` entries, y receives `rows` entries (overwritten). Each y[r] is the sum
    // of double(data[i]) * double(x[indices[i]]) over the row's nonzeros, accumulated in double in
    // index order, so the result is deterministic (it does not depend on threads or scheduling).
    // The matrix must be valid (check() empty); x and y must not overlap.
    void multiply(const float* x, double* y) const;
};

// The same shape, structure and value bits (memcmp of the values: -0 differs from 0): what "the
// same T" means for reproducibility (a seed whatever the thread count, a pixel subset).
bool bit_identical(const CsrMatrix& a, const CsrMatrix& b);

}  // namespace ltm
