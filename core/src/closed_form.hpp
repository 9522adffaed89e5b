// The block algebra of pinrate.solvers.closed_form and pinrate.solvers.eigen, on doubles.
//
// Every expression keeps the Python source's order of operations (left to right, no fused
// multiply-add: the build passes -ffp-contract=off), so a kernel here returns the same
// double as its Python twin, bit for bit, for the same input.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>

#include "boundary.hpp"

namespace pinrate_core {

// A square block of size 0 to 3 (row-major) or a rectangular one up to 3x3.
struct Block {
  int rows = 0;
  int cols = 0;
  std::array<double, 9> v{};
  double operator()(int r, int c) const { return v[3 * r + c]; }
  double &operator()(int r, int c) { return v[3 * r + c]; }
};

struct Vec3 {
  int n = 0;
  std::array<double, 3> v{};
  double operator[](int i) const { return v[i]; }
  double &operator[](int i) { return v[i]; }
};

// A singular square block: the step goes back to Python, which raises and reports it.
struct Singular : std::runtime_error {
  explicit Singular(const std::string &block) : std::runtime_error(block) {}
};

// singular.invertible: det^2 > ratio^2 * prod_j ||M[:, j]||^2 (False for NaN).
inline bool invertible(double det, double scale_squared) { return det * det > kSingularRatioSquared * scale_squared; }

// closed_form._dot: a0 b0 + a1 b1 + a2 b2, left to right.
inline double dot(const double *a, const double *b, int n, int stride_a = 1, int stride_b = 1) {
  if (n == 0) return 0.0;
  double sum = a[0] * b[0];
  for (int i = 1; i < n; ++i) sum = sum + a[i * stride_a] * b[i * stride_b];
  return sum;
}

inline double column_dot(const Block &M, int c) {
  double column[3];
  for (int r = 0; r < M.rows; ++r) column[r] = M(r, c);
  return dot(column, column, M.rows);
}

// closed_form._singular for the 1x1 and 2x2 cases: scale_squared = 1.0 * col_0 . col_0 * ...
inline void check_singular(double det, const Block &M, const char *block) {
  double scale_squared = 1.0;
  for (int c = 0; c < M.cols; ++c) scale_squared *= column_dot(M, c);
  if (!invertible(det, scale_squared)) throw Singular(block);
}

// closed_form.solve: x with M x = b (Cramer's rule), sizes 0 to 3. The 3x3 case repeats
// inverse()'s cofactors on purpose, as the Python does: fused with the product, it skips M^-1.
inline Vec3 solve(const Block &M, const Vec3 &b, const char *block) {
  Vec3 x;
  x.n = M.rows;
  if (M.rows == 3) {
    const double a = M(0, 0), b_ = M(0, 1), c = M(0, 2), d = M(1, 0), e = M(1, 1), f = M(1, 2), g = M(2, 0),
                 h = M(2, 1), i = M(2, 2);
    const double c0 = e * i - f * h, c1 = f * g - d * i, c2 = d * h - e * g;
    const double det = a * c0 + b_ * c1 + c * c2;
    const double scale_squared = (a * a + d * d + g * g) * (b_ * b_ + e * e + h * h) * (c * c + f * f + i * i);
    if (!invertible(det, scale_squared)) throw Singular(block);
    const double x0 = b[0], y = b[1], z = b[2];
    const double inv = 1.0 / det;
    x[0] = (c0 * x0 + (c * h - b_ * i) * y + (b_ * f - c * e) * z) * inv;
    x[1] = (c1 * x0 + (a * i - c * g) * y + (c * d - a * f) * z) * inv;
    x[2] = (c2 * x0 + (b_ * g - a * h) * y + (a * e - b_ * d) * z) * inv;
  } else if (M.rows == 2) {
    const double a = M(0, 0), b_ = M(0, 1), c = M(1, 0), d = M(1, 1);
    const double det = a * d - b_ * c;
    check_singular(det, M, block);
    x[0] = (d * b[0] - b_ * b[1]) / det;
    x[1] = (a * b[1] - c * b[0]) / det;
  } else if (M.rows == 1) {
    check_singular(M(0, 0), M, block);
    x[0] = b[0] / M(0, 0);
  }
  return x;
}

// closed_form.inverse: the adjugate times 1/det (3x3), over det (2x2), 1/M (1x1).
inline Block inverse(const Block &M, const char *block) {
  Block R;
  R.rows = M.cols;
  R.cols = M.rows;
  if (M.rows == 3) {
    const double a = M(0, 0), b = M(0, 1), c = M(0, 2), d = M(1, 0), e = M(1, 1), f = M(1, 2), g = M(2, 0),
                 h = M(2, 1), i = M(2, 2);
    const double c0 = e * i - f * h, c1 = f * g - d * i, c2 = d * h - e * g;
    const double det = a * c0 + b * c1 + c * c2;
    const double scale_squared = (a * a + d * d + g * g) * (b * b + e * e + h * h) * (c * c + f * f + i * i);
    if (!invertible(det, scale_squared)) throw Singular(block);
    const double s = 1.0 / det;
    R.v = {c0 * s, (c * h - b * i) * s, (b * f - c * e) * s, c1 * s, (a * i - c * g) * s,
           (c * d - a * f) * s, c2 * s, (b * g - a * h) * s, (a * e - b * d) * s};
  } else if (M.rows == 2) {
    const double a = M(0, 0), b = M(0, 1), c = M(1, 0), d = M(1, 1);
    const double det = a * d - b * c;
    check_singular(det, M, block);
    R(0, 0) = d / det;
    R(0, 1) = -b / det;
    R(1, 0) = -c / det;
    R(1, 1) = a / det;
  } else if (M.rows == 1) {
    check_singular(M(0, 0), M, block);
    R(0, 0) = 1.0 / M(0, 0);
  }
  return R;
}

inline Vec3 matvec(const Block &M, const Vec3 &x) {
  Vec3 y;
  y.n = M.rows;
  for (int r = 0; r < M.rows; ++r) y[r] = dot(&M.v[3 * r], x.v.data(), M.cols);
  return y;
}

// closed_form._minus_matvec: a - M x.
inline Vec3 minus_matvec(const Vec3 &a, const Block &M, const Vec3 &x) {
  Vec3 y;
  y.n = a.n;
  for (int r = 0; r < a.n; ++r) y[r] = a[r] - dot(&M.v[3 * r], x.v.data(), M.cols);
  return y;
}

// closed_form._matmul: the explicit 3x3 product, else row . column.
inline Block matmul(const Block &X, const Block &Y) {
  Block Z;
  Z.rows = X.rows;
  Z.cols = Y.cols;
  if (X.rows == 3 && X.cols == 3 && Y.cols == 3) {  // a 6-DOF arm's: unrolled, the same sums in the same order
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Z.v[3 * r + c] = X.v[3 * r] * Y.v[c] + X.v[3 * r + 1] * Y.v[3 + c] + X.v[3 * r + 2] * Y.v[6 + c];
    return Z;
  }
  for (int r = 0; r < X.rows; ++r)
    for (int c = 0; c < Y.cols; ++c) Z(r, c) = dot(&X.v[3 * r], &Y.v[c], X.cols, 1, 3);
  return Z;
}

struct Rates {  // arm rates then wrist rates
  Vec3 arm, wrist;
};

inline Rates mca1(const Block &A, const Block &B, const Block &, const Block &W, const Vec3 &v, const Vec3 &omega) {
  Rates out;
  out.wrist = solve(W, omega, "W");
  out.arm = solve(A, minus_matvec(v, B, out.wrist), "A");
  return out;
}

inline Rates mca2(const Block &A, const Block &, const Block &U, const Block &W, const Vec3 &v, const Vec3 &omega) {
  Rates out;
  out.arm = solve(A, v, "A");
  out.wrist = solve(W, minus_matvec(omega, U, out.arm), "W");
  return out;
}

inline Rates mca3(const Block &A, const Block &B, const Block &U, const Block &W, const Vec3 &v, const Vec3 &omega) {
  const Block A_inv = inverse(A, "A"), W_inv = inverse(W, "W");
  const Vec3 wrist_only = matvec(W_inv, omega), arm_only = matvec(A_inv, v);
  Rates out;
  out.arm = matvec(A_inv, minus_matvec(v, B, wrist_only));
  out.wrist = matvec(W_inv, minus_matvec(omega, U, arm_only));
  return out;
}

inline Rates schur(const Block &A, const Block &B, const Block &U, const Block &W, const Vec3 &v, const Vec3 &omega) {
  const int k = W.rows, n = A.rows;
  Vec3 columns[3];  // W^-1 U, column by column
  for (int c = 0; c < n; ++c) {
    Vec3 column;
    column.n = k;
    for (int r = 0; r < k; ++r) column[r] = U(r, c);
    columns[c] = solve(W, column, "W");
  }
  Block complement;
  complement.rows = complement.cols = n;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      double sum = 0.0;  // Python's sum() starts from 0
      for (int j = 0; j < k; ++j) sum = sum + B(r, j) * columns[c][j];
      complement(r, c) = A(r, c) - sum;
    }
  Rates out;
  out.arm = solve(complement, minus_matvec(v, B, solve(W, omega, "W")), "A - B W^-1 U");
  out.wrist = solve(W, minus_matvec(omega, U, out.arm), "W");
  return out;
}

// --- eigen.spectral_radius_2 / _3 with eigen.FLOATS -------------------------------------
inline double py_max(double a, double b) { return b > a ? b : a; }  // Python's max(a, b)
inline double py_min(double a, double b) { return b < a ? b : a; }

inline double spectral_radius_2(double a, double b, double c, double d) {
  const double half_difference = (a - d) * 0.5;
  const double discriminant = half_difference * half_difference + b * c;
  if (discriminant >= 0.0) return std::fabs((a + d) * 0.5) + std::sqrt(py_max(discriminant, 0.0));
  return std::sqrt(py_max(a * d - b * c, 0.0));
}

inline double spectral_radius_3(const Block &M) {
  double a = M(0, 0), b = M(0, 1), c = M(0, 2), d = M(1, 0), e = M(1, 1), f = M(1, 2), g = M(2, 0), h = M(2, 1),
         i = M(2, 2);
  const double shift = (a + e + i) * (1.0 / 3.0);
  a = a - shift;
  e = e - shift;
  i = i - shift;
  const double minor_ei = e * i, minor_fh = f * h;
  const double p = (a * e - b * d) + (a * i - c * g) + (minor_ei - minor_fh);
  const double q = -(a * (minor_ei - minor_fh) - b * (d * i - f * g) + c * (d * h - e * g));
  const double half_q = 0.5 * q;
  const double third_p = p * (1.0 / 3.0);
  const double discriminant = half_q * half_q + third_p * third_p * third_p;
  if (discriminant > 0.0) {  // Cardano
    const double root = std::sqrt(py_max(discriminant, 0.0));
    const double w = half_q >= 0.0 ? -half_q - root : -half_q + root;
    const double u = std::copysign(std::pow(std::fabs(w), 1.0 / 3.0), w);
    const double v = -third_p / (u == 0.0 ? 1.0 : u);
    const double real_part = -(u + v) * 0.5 + shift;
    const double imaginary_part = (std::sqrt(3.0) / 2.0) * (u - v);
    return py_max(std::fabs(u + v + shift), std::hypot(real_part, imaginary_part));
  }
  // Viete: the largest root (k = 0, cos in [1/2, 1]) and the smallest (k = 2, cos(angle + 2 pi / 3)
  // by the angle sum) bracket the middle one, so rho is the larger of their two magnitudes.
  const bool flat = p >= -kFlat;
  if (flat) return std::fabs(shift);
  const double radius = 2.0 * std::sqrt(-p * (1.0 / 3.0));
  const double angle = std::acos(py_max(-1.0, py_min(1.0, 3.0 * q / (p * radius)))) * (1.0 / 3.0);
  const double cosine = std::cos(angle), sine = std::sin(angle);
  const double largest = radius * cosine + shift;
  const double smallest = -radius * (0.5 * cosine + (std::sqrt(3.0) / 2.0) * sine) + shift;
  return py_max(std::fabs(largest), std::fabs(smallest));
}

// The largest |eigenvalue| of a square Block, 0 of an empty one (closed_form.spectral_radius's end).
inline double block_radius(const Block &M) {
  if (M.rows == 3) return spectral_radius_3(M);
  if (M.rows == 2) return spectral_radius_2(M(0, 0), M(0, 1), M(1, 0), M(1, 1));
  if (M.rows == 1) return std::fabs(M(0, 0));
  return 0.0;
}

// closed_form.blocks for one partition, its indexing done once: where each entry of A, B, U
// and W sits in J's column-major storage (6 rows), so a map reads 9 doubles per block per q
// instead of walking the partition's row and column lists.
struct BlockLayout {
  std::array<Block, 4> shapes;                // A, B, U, W: rows and cols (values unused)
  std::array<std::array<int, 9>, 4> offsets{};  // [block][3 r + c]: index into J's data

  BlockLayout() = default;  // no blocks (a partition the closed forms do not take)
  BlockLayout(const int *rows, const int *columns, int m, int k, int n_arm, int n) {
    const int spec[4][4] = {{0, m, 0, n_arm}, {0, m, n_arm, n - n_arm}, {m, k, 0, n_arm}, {m, k, n_arm, n - n_arm}};
    for (int b = 0; b < 4; ++b) {
      shapes[b].rows = spec[b][1];
      shapes[b].cols = spec[b][3];
      offsets[b].fill(0);
      for (int r = 0; r < spec[b][1]; ++r)
        for (int c = 0; c < spec[b][3]; ++c) offsets[b][3 * r + c] = 6 * columns[spec[b][2] + c] + rows[spec[b][0] + r];
    }
  }

  // A, B, U, W of the J whose column-major data starts at `jacobian`; a 3x3 block in one sweep.
  void gather(const double *jacobian, Block &A, Block &B, Block &U, Block &W) const {
    Block *out[4] = {&A, &B, &U, &W};
    for (int b = 0; b < 4; ++b) {
      Block &M = *out[b];
      M.rows = shapes[b].rows;
      M.cols = shapes[b].cols;
      if (M.rows == 3 && M.cols == 3) {
        for (int t = 0; t < 9; ++t) M.v[t] = jacobian[offsets[b][t]];
        continue;
      }
      for (int r = 0; r < M.rows; ++r)
        for (int c = 0; c < M.cols; ++c) M.v[3 * r + c] = jacobian[offsets[b][3 * r + c]];
    }
  }
};

// closed_form.spectral_radius: rho of the smaller of G = U A^-1 B W^-1 and H (eq. 32, 50).
inline double spectral_radius(const Block &A, const Block &B, const Block &U, const Block &W) {
  const Block P = matmul(U, inverse(A, "A"));  // k x m
  const Block Q = matmul(B, inverse(W, "W"));  // m x k
  return block_radius(P.rows <= Q.rows ? matmul(P, Q) : matmul(Q, P));
}

// conditioning.inverse_condition_bound on nested lists: 1 / (||M||_F ||M^-1||_F).
inline double inverse_condition_bound(const Block &M, const Block &M_inverse) {
  double matrix_norm2 = 0.0, inverse_norm2 = 0.0;  // sum() from 0, row by row
  for (int r = 0; r < M.rows; ++r)
    for (int c = 0; c < M.cols; ++c) matrix_norm2 = matrix_norm2 + M(r, c) * M(r, c);
  for (int r = 0; r < M_inverse.rows; ++r)
    for (int c = 0; c < M_inverse.cols; ++c) inverse_norm2 = inverse_norm2 + M_inverse(r, c) * M_inverse(r, c);
  const double product = matrix_norm2 * inverse_norm2;
  if (!(product > 0.0) || !std::isfinite(product)) return 0.0;
  return 1.0 / std::sqrt(product);
}

}  // namespace pinrate_core
