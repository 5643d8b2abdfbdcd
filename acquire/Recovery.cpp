#include "acquire/Recovery.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ltm::acquire {

OmpResult omp(const std::vector<double>& A_data, int K, int n, const std::vector<double>& z_data, const OmpOptions& o) {
    if (K < 1 || n < 0 || A_data.size() != static_cast<std::size_t>(K) * n || z_data.size() != static_cast<std::size_t>(K))
        throw std::invalid_argument("omp: the dictionary is not K x n or z does not have K values");
    const Eigen::Map<const Eigen::MatrixXd> A(A_data.data(), K, n);
    const Eigen::Map<const Eigen::VectorXd> z(z_data.data(), K);
    const Eigen::VectorXd norms = A.colwise().norm().transpose();
    const int max_atoms = std::min({o.max_atoms > 0 ? o.max_atoms : n, n, K});

    OmpResult r;
    Eigen::VectorXd residual = z;
    r.residual_squared = residual.squaredNorm();
    std::vector<char> picked(static_cast<std::size_t>(n), 0);
    Eigen::VectorXd coef;
    while (static_cast<int>(r.support.size()) < max_atoms && r.residual_squared > o.residual_squared) {
        const Eigen::VectorXd corr = A.transpose() * residual;
        int best = -1;
        double best_score = 0;
        for (int j = 0; j < n; ++j) {
            if (picked[static_cast<std::size_t>(j)] || !(norms[j] > 0)) continue;
            const double c = corr[j] / norms[j];
            const double score = o.nonnegative ? c : std::fabs(c);
            if (score > best_score) {
                best_score = score;
                best = j;
            }
        }
        if (best < 0) break;  // nothing correlates with the residual any more
        picked[static_cast<std::size_t>(best)] = 1;
        r.support.push_back(best);
        Eigen::MatrixXd As(K, static_cast<Eigen::Index>(r.support.size()));
        for (std::size_t i = 0; i < r.support.size(); ++i) As.col(static_cast<Eigen::Index>(i)) = A.col(r.support[i]);
        coef = As.colPivHouseholderQr().solve(z);
        residual = z - As * coef;
        r.residual_squared = residual.squaredNorm();
    }
    r.values.assign(coef.data(), coef.data() + coef.size());
    return r;
}

double mutual_coherence(const std::vector<double>& A_data, int K, int n) {
    const Eigen::Map<const Eigen::MatrixXd> A(A_data.data(), K, n);
    Eigen::MatrixXd U = A;
    for (int j = 0; j < n; ++j)
        if (U.col(j).norm() > 0) U.col(j).normalize();
    const Eigen::MatrixXd G = U.transpose() * U;
    double mu = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < i; ++j) mu = std::max(mu, std::fabs(G(i, j)));
    return mu;
}

int compressive_patterns(int s, long n, double delta) {
    const double t = 2.0 * s - 1.0;
    return static_cast<int>(std::ceil(2.0 * t * t * std::log(static_cast<double>(n) * static_cast<double>(n) / delta)));
}

}  // namespace ltm::acquire
