// The block algebra of pinrate.solvers.reference (the servo's rates) and of
// pinrate.solvers.batched (rho) for blocks of any shape (a 7-DOF arm's 3x4 A, a 4-DOF arm's
// 3x1 W), on Eigen: pseudo-inverses where the closed forms of closed_form.hpp do not apply.
// numpy's LAPACK and these factorizations round differently, so the two paths agree here to
// about 1e-15 relative times the blocks' conditioning, not to the bit.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include "closed_form.hpp"

namespace pinrate_core {

using Matrix = Eigen::MatrixXd;

// numpy.linalg.pinv(M, rcond): V diag(1/s for s > rcond s_max) U^T.
inline Matrix pinv(const Matrix &M, double rcond) {
  if (M.size() == 0) return Matrix::Zero(M.cols(), M.rows());
  Eigen::JacobiSVD<Matrix> svd(M, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd &s = svd.singularValues();
  const double cutoff = rcond * (s.size() ? s.maxCoeff() : 0.0);
  Eigen::VectorXd inverted(s.size());
  for (int i = 0; i < s.size(); ++i) inverted[i] = s[i] > cutoff ? 1.0 / s[i] : 0.0;
  return svd.matrixV() * inverted.asDiagonal() * svd.matrixU().transpose();
}

// reference.inverse: M^-1 of a square block the singularity rule accepts, M^+ of a
// rectangular one, zeros of an empty one. Throws Singular.
inline Matrix reference_inverse(const Matrix &M, const char *block, double rcond) {
  if (M.rows() == 0 || M.cols() == 0) return Matrix::Zero(M.cols(), M.rows());
  if (M.rows() != M.cols()) return pinv(M, rcond);
  Eigen::PartialPivLU<Matrix> lu(M);
  double scale_squared = 1.0;
  for (int c = 0; c < M.cols(); ++c) scale_squared *= M.col(c).squaredNorm();
  if (!invertible(lu.determinant(), scale_squared)) throw Singular(block);
  return lu.inverse();
}

struct GeneralRates {
  Eigen::VectorXd arm, wrist;
};

// reference.mca1 / mca2 / mca3 / schur with reference.inverse.
inline GeneralRates general_kernel(Kernel kernel, const Matrix &A, const Matrix &B, const Matrix &U, const Matrix &W,
                                   const Eigen::VectorXd &v, const Eigen::VectorXd &omega, double rcond) {
  GeneralRates out;
  if (kernel == SCHUR) {
    const Matrix W_inv = reference_inverse(W, "W", rcond);
    const Matrix complement = A - B * W_inv * U;
    out.arm = reference_inverse(complement, "A - B W^-1 U", rcond) * (v - B * (W_inv * omega));
    out.wrist = W_inv * (omega - U * out.arm);
    return out;
  }
  const Matrix A_inv = reference_inverse(A, "A", rcond), W_inv = reference_inverse(W, "W", rcond);
  if (kernel == MCA1) {
    out.wrist = W_inv * omega;
    out.arm = A_inv * (v - B * out.wrist);
  } else if (kernel == MCA2) {
    out.arm = A_inv * v;
    out.wrist = W_inv * (omega - U * out.arm);
  } else {  // MCA3
    out.arm = A_inv * (v - B * (W_inv * omega));
    out.wrist = W_inv * (omega - U * (A_inv * v));
  }
  return out;
}

// A general block's matrices with at most kCapped rows and columns live on the stack: the rho
// map allocates nothing per q on a partition of up to kCapped joints (wider ones use Matrix).
constexpr int kCapped = 12;
using Capped = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kCapped, kCapped>;

// M^+ of a rectangular M of full rank whose shorter side q is at most 3, from T = Q R, T its
// tall orientation (p x q), by classical Gram-Schmidt with one reorthogonalization (Q
// orthonormal to rounding, T + dT = Q R with ||dT|| of order eps ||T||: backward stable like
// numpy's SVD): M^+ = R^-1 Q^T, or Q R^-T for a wide M. Where ||R||_F ||R^-1||_F (at least
// sigma_max / sigma_min) is below 1 / (100 rcond), no singular value falls under
// numpy.linalg.pinv's cutoff, so M^+ is pinv's matrix; else false (the cutoff decides: the SVD).
template <typename M>
bool full_rank_pinv(const M &A, double rcond, M &out) {
  const bool tall = A.rows() > A.cols();
  const int p = static_cast<int>(tall ? A.rows() : A.cols()), q = static_cast<int>(tall ? A.cols() : A.rows());
  if (q > 3 || p > kCapped) return false;
  double Q[3][kCapped];  // Q's columns
  double R[3][3] = {}, R_inv[3][3] = {};
  for (int j = 0; j < q; ++j) {
    double *v = Q[j];
    for (int i = 0; i < p; ++i) v[i] = tall ? A(i, j) : A(j, i);
    for (int pass = 0; pass < 2; ++pass)
      for (int l = 0; l < j; ++l) {
        const double h = dot(Q[l], v, p);
        R[l][j] = R[l][j] + h;
        for (int i = 0; i < p; ++i) v[i] = v[i] - h * Q[l][i];
      }
    const double norm = std::sqrt(dot(v, v, p));
    if (!(norm > 0.0)) return false;
    R[j][j] = norm;
    const double scale = 1.0 / norm;
    for (int i = 0; i < p; ++i) v[i] = v[i] * scale;
  }
  double norm2 = 0.0, inverse_norm2 = 0.0;
  for (int j = q - 1; j >= 0; --j) {  // R^-1, upper triangular, column by column from the last
    R_inv[j][j] = 1.0 / R[j][j];
    for (int c = j + 1; c < q; ++c) {
      double sum = 0.0;
      for (int l = j + 1; l <= c; ++l) sum = sum + R[j][l] * R_inv[l][c];
      R_inv[j][c] = -sum / R[j][j];
    }
  }
  for (int r = 0; r < q; ++r)
    for (int c = r; c < q; ++c) norm2 = norm2 + R[r][c] * R[r][c], inverse_norm2 = inverse_norm2 + R_inv[r][c] * R_inv[r][c];
  const double bound = 1.0 / (100.0 * rcond);
  if (!(norm2 * inverse_norm2 < bound * bound)) return false;
  out.resize(A.cols(), A.rows());
  for (int i = 0; i < p; ++i)  // (R^-1 Q^T)(r, i) = sum_c R_inv[r][c] Q[c][i]
    for (int r = 0; r < q; ++r) {
      double sum = 0.0;
      for (int c = r; c < q; ++c) sum = sum + R_inv[r][c] * Q[c][i];
      if (tall)
        out(r, i) = sum;
      else
        out(i, r) = sum;
    }
  return true;
}

// batched.inverse, one block: the adjugate of a square block (closed_form.inverse; A and W
// have at most 3 rows, so a square one is at most 3x3), M^+ of a rectangular one, zeros of an
// empty one. Throws Singular.
template <typename M>
M map_inverse(const M &A, const char *block, double rcond) {
  if (A.rows() == 0 || A.cols() == 0) return M::Zero(A.cols(), A.rows());
  if (A.rows() != A.cols()) {
    M out;
    if (full_rank_pinv(A, rcond, out)) return out;
    Eigen::JacobiSVD<M> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto &s = svd.singularValues();
    const double cutoff = rcond * s.maxCoeff();
    M V = svd.matrixV();
    for (int i = 0; i < s.size(); ++i) V.col(i) *= s[i] > cutoff ? 1.0 / s[i] : 0.0;
    return V * svd.matrixU().transpose();
  }
  const int n = static_cast<int>(A.rows());
  if (n > 3) throw std::invalid_argument("a square block larger than 3x3");
  Block small;
  small.rows = small.cols = n;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) small(r, c) = A(r, c);
  const Block inverted = inverse(small, block);
  M out(n, n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) out(r, c) = inverted(r, c);
  return out;
}

// X Y as a Block, for a product of at most 3 x 3 (any inner size): row . column, left to right.
template <typename MX, typename MY>
Block product_block(const MX &X, const MY &Y) {
  Block Z;
  Z.rows = static_cast<int>(X.rows());
  Z.cols = static_cast<int>(Y.cols());
  const int inner = static_cast<int>(X.cols());
  for (int r = 0; r < Z.rows; ++r)
    for (int c = 0; c < Z.cols; ++c) {
      double sum = inner ? X(r, 0) * Y(0, c) : 0.0;
      for (int j = 1; j < inner; ++j) sum = sum + X(r, j) * Y(j, c);
      Z(r, c) = sum;
    }
  return Z;
}

// batched.spectral_radius, one configuration: rho of the smaller of G = U A^+ B W^+ and H (A
// not tall, W not wide: the pseudo-inverse G has the error map's spectrum); inf where a square
// block is singular. P = U A^+ (k x m) and Q = B W^+ (m x k) have at most 3 rows and columns
// whatever the joints, so G and H are Blocks and take the closed forms.
template <typename M>
double block_spectral_radius(const M &A, const M &B, const M &U, const M &W, double rcond) {
  try {
    const Block P = product_block(U, map_inverse<M>(A, "A", rcond));
    const Block Q = product_block(B, map_inverse<M>(W, "W", rcond));
    return block_radius(P.rows <= Q.rows ? matmul(P, Q) : matmul(Q, P));
  } catch (const Singular &) {
    return INFINITY;
  }
}

// The same for blocks of any size: on the stack up to kCapped rows and columns.
inline double general_spectral_radius(const Matrix &A, const Matrix &B, const Matrix &U, const Matrix &W,
                                      double rcond) {
  if (A.cols() + B.cols() <= kCapped && A.rows() + U.rows() <= kCapped)
    return block_spectral_radius<Capped>(A, B, U, W, rcond);
  return block_spectral_radius<Matrix>(A, B, U, W, rcond);
}

// conditioning.inverse_condition: sigma_rank / sigma_1 (0 for a zero block).
inline double inverse_condition(const Matrix &M, int rank) {
  Eigen::JacobiSVD<Matrix> svd(M);
  const Eigen::VectorXd &s = svd.singularValues();
  return s[0] > 0.0 ? s[rank - 1] / s[0] : 0.0;
}

}  // namespace pinrate_core
