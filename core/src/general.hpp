// The block algebra of pinrate.solvers.reference for blocks of any shape (a 7-DOF arm's 3x4
// A, a 4-DOF arm's 3x1 W), on Eigen: pseudo-inverses and eigenvalues where the closed forms
// of closed_form.hpp do not apply. numpy's LAPACK and Eigen's SVD round differently, so the
// two paths agree here to about 1e-15 relative, not to the bit.
#pragma once

#include <Eigen/Dense>
#include <cmath>

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

// The largest |eigenvalue| of a square matrix: the closed forms up to 3x3, Eigen above.
inline double matrix_spectral_radius(const Matrix &M) {
  const int n = static_cast<int>(M.rows());
  if (n == 0) return 0.0;
  if (n <= 3) {
    Block small;
    small.rows = small.cols = n;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) small(r, c) = M(r, c);
    if (n == 3) return spectral_radius_3(small);
    if (n == 2) return spectral_radius_2(small(0, 0), small(0, 1), small(1, 0), small(1, 1));
    return std::fabs(small(0, 0));
  }
  return Eigen::EigenSolver<Matrix>(M, false).eigenvalues().cwiseAbs().maxCoeff();
}

// reference.spectral_radius: rho of the smaller of G = U A^+ B W^+ and H (A not tall, W not
// wide: the pseudo-inverse G has the error map's spectrum); inf where a square block is singular.
inline double general_spectral_radius(const Matrix &A, const Matrix &B, const Matrix &U, const Matrix &W,
                                      double rcond) {
  try {
    const Matrix P = U * reference_inverse(A, "A", rcond);
    const Matrix Q = B * reference_inverse(W, "W", rcond);
    return P.rows() <= Q.rows() ? matrix_spectral_radius(P * Q) : matrix_spectral_radius(Q * P);
  } catch (const Singular &) {
    return INFINITY;
  }
}

// conditioning.inverse_condition: sigma_rank / sigma_1 (0 for a zero block).
inline double inverse_condition(const Matrix &M, int rank) {
  Eigen::JacobiSVD<Matrix> svd(M);
  const Eigen::VectorXd &s = svd.singularValues();
  return s[0] > 0.0 ? s[rank - 1] / s[0] : 0.0;
}

}  // namespace pinrate_core
