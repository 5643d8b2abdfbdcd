#include "io/CsrMatrix.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace ltm {

bool bit_identical(const CsrMatrix& a, const CsrMatrix& b) {
    return a.rows == b.rows && a.cols == b.cols && a.indptr == b.indptr && a.indices == b.indices &&
           a.data.size() == b.data.size() &&
           (a.data.empty() || std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0);
}

CsrMatrix CsrMatrix::zeros(std::int64_t rows, std::int64_t cols) {
    CsrMatrix m;
    m.rows = rows;
    m.cols = cols;
    m.indptr.assign(rows >= 0 ? static_cast<std::size_t>(rows) + 1 : 1, 0);
    return m;
}

std::string CsrMatrix::check() const {
    std::ostringstream os;
    if (rows < 0 || cols < 0) {
        os << "negative shape (" << rows << ", " << cols << ")";
        return os.str();
    }
    if (indices.size() != data.size()) {
        os << "indices has " << indices.size() << " entries but data has " << data.size();
        return os.str();
    }
    if (indptr.size() != static_cast<std::uint64_t>(rows) + 1) {
        os << "indptr has " << indptr.size() << " entries, expected rows + 1 = " << rows + 1;
        return os.str();
    }
    if (indptr[0] != 0) {
        os << "indptr[0] = " << indptr[0] << ", expected 0";
        return os.str();
    }
    const auto nz = static_cast<std::int64_t>(data.size());
    if (indptr[static_cast<std::size_t>(rows)] != nz) {
        os << "indptr[" << rows << "] = " << indptr[static_cast<std::size_t>(rows)]
           << " (the last entry) differs from the number of nonzeros " << nz;
        return os.str();
    }
    for (std::int64_t r = 0; r < rows; ++r) {
        const std::int64_t b = indptr[static_cast<std::size_t>(r)], e = indptr[static_cast<std::size_t>(r) + 1];
        if (e < b) {
            os << "indptr decreases at row " << r << " (indptr[" << r << "] = " << b << ", indptr[" << r + 1
               << "] = " << e << ")";
            return os.str();
        }
        if (e > nz) {
            os << "indptr[" << r + 1 << "] = " << e << " exceeds the number of nonzeros " << nz;
            return os.str();
        }
        // The row is good when its columns strictly increase from one >= 0 to one < cols: checked
        // branch-free first (a render's T is checked before it is written, 10^7 nonzeros at
        // industrial scale), and looked at one by one only to say what is wrong.
        if (b == e) continue;
        bool increasing = true;
        for (auto i = static_cast<std::size_t>(b) + 1; i < static_cast<std::size_t>(e); ++i)
            increasing &= indices[i] > indices[i - 1];
        if (increasing && indices[static_cast<std::size_t>(b)] >= 0 &&
            static_cast<std::int64_t>(indices[static_cast<std::size_t>(e) - 1]) < cols)
            continue;
        for (std::int64_t i = b; i < e; ++i) {
            const std::int64_t c = indices[static_cast<std::size_t>(i)];
            if (c < 0 || c >= cols) {
                os << "column index " << c << " of nonzero " << i << " (row " << r << ") is outside [0, " << cols
                   << ")";
                return os.str();
            }
            if (i > b && c <= indices[static_cast<std::size_t>(i) - 1]) {
                os << "column indices of row " << r << " are not strictly increasing (nonzero " << i
                   << " has column " << c << " after column " << indices[static_cast<std::size_t>(i) - 1]
                   << "): unsorted or duplicate entries";
                return os.str();
            }
        }
    }
    bool finite = true;  // branch-free first, as the columns
    for (const float v : data) finite &= std::fabs(v) <= std::numeric_limits<float>::max();
    if (finite) return {};
    for (std::size_t i = 0; i < data.size(); ++i) {
        if (!std::isfinite(data[i])) {
            os << "value of nonzero " << i << " is " << data[i] << ", not a finite number";
            return os.str();
        }
    }
    return {};
}

void CsrMatrix::multiply(const float* x, double* y) const {
    for (std::int64_t r = 0; r < rows; ++r) {
        double sum = 0.0;
        const auto e = static_cast<std::size_t>(indptr[static_cast<std::size_t>(r) + 1]);
        for (auto i = static_cast<std::size_t>(indptr[static_cast<std::size_t>(r)]); i < e; ++i)
            sum += static_cast<double>(data[i]) * static_cast<double>(x[indices[i]]);
        y[r] = sum;
    }
}

}  // namespace ltm
