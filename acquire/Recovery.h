#pragma once
// Sparse recovery of one row of T from compressive measurements: orthogonal matching pursuit
// (Y. C. Pati, R. Rezaiifar and P. S. Krishnaprasad, "Orthogonal matching pursuit: recursive
// function approximation with applications to wavelet decomposition", Asilomar 1993).
//
// Problem: z = A t + e, A a K x n dictionary (K measurements, n candidate display pixels), t
// s-sparse. OMP picks, s times, the column most correlated with the residual and re-fits all
// picked columns by least squares (Eigen's column-pivoting Householder QR).
//
// The guarantee the tests check (J. A. Tropp, "Greed is good: algorithmic results for sparse
// approximation", IEEE Trans. Inf. Theory 50 (2004) 2231-2242, Theorem A with Corollary 3.6;
// D. L. Donoho and M. Elad, PNAS 100 (2003) 2197-2202): with unit-norm columns and mutual
// coherence mu = max_{i != j} |<a_i, a_j>|, OMP recovers EVERY s-sparse t exactly from noise-free
// z when s < (1 + 1/mu) / 2, whatever t's values and signs.
//
// How many patterns that takes (kept with the code that relies on it, compressive_patterns):
// for K independent random +-1 patterns (each entry +1 or -1 with probability 1/2, centred), a
// pair's normalised inner product is a mean of K independent +-1 values, so by Hoeffding
// P(|<a_i, a_j>| >= t) <= 2 exp(-K t^2 / 2); a union bound over the n (n - 1) / 2 pairs gives
// mu < t with probability >= 1 - delta for t = sqrt(2 ln(n^2 / delta) / K). The guarantee needs
// mu < 1 / (2 s - 1), so
//     K >= 2 (2 s - 1)^2 ln(n^2 / delta)
// patterns suffice with probability >= 1 - delta. (Weaker, average-case statements need only
// K ~ 4 s ln(n / delta): Tropp and Gilbert, IEEE Trans. Inf. Theory 53 (2007) 4655-4666; the
// measured table in docs/acquisition.md shows what is needed in practice.)
#include <vector>

namespace ltm::acquire {

struct OmpOptions {
    int max_atoms = 0;              // s at most (<= min(K, n)); 0: min(K, n)
    double residual_squared = 0.0;  // stop once |z - A t|^2 <= this (noise: K sigma^2 and a margin)
    bool nonnegative = false;       // pick only positively correlated columns (T >= 0)
};

struct OmpResult {
    std::vector<int> support;       // picked columns, in the order picked
    std::vector<double> values;     // their coefficients
    double residual_squared = 0;
};

// A is column-major, K x n (A[i + K * j] = A(i, j)); z has K values. Columns need not be
// normalised (the selection uses correlations divided by the column norms; zero columns are never
// picked). Throws std::invalid_argument for mismatched sizes.
OmpResult omp(const std::vector<double>& A, int K, int n, const std::vector<double>& z, const OmpOptions& options);

// The mutual coherence of A's columns (normalised), 0 for n < 2.
double mutual_coherence(const std::vector<double>& A, int K, int n);

// The number of +-1 patterns that guarantee exact recovery of every s-sparse vector over n
// candidates with probability >= 1 - delta (above): ceil(2 (2 s - 1)^2 ln(n^2 / delta)).
int compressive_patterns(int s, long n, double delta);

}  // namespace ltm::acquire
