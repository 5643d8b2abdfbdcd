#include "io/CsrMatrix.h"

#include <cmath>
#include <cstring>
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
