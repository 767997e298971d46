// Private: Eigen's dense decompositions, compiled once for the whole library.
//
// Each source file that uses, say, a JacobiSVD<MatrixXd> otherwise compiles all of it again, and
// with GCC these few classes were most of the build time of the files that use them (a minute
// for the SVDs alone in some). The declarations below tell the compiler that their code is
// compiled in eigen_instances.cpp; include it in the library's source files that use them. Small
// inline members are still inlined where they are used. (Tests and programs that use only a few
// members gain nothing measurable from it and do not include it.) One SVD serves the library,
// JacobiSVD over MatrixXd (3 × n point sets included), at most ~100 columns, where a one-sided
// Jacobi after a QR costs little more than BDCSVD; ranks come from a column-pivoted QR. BDCSVD
// and a fixed-row JacobiSVD each added 20–40 s of compilation per compiler.
#pragma once

#include <Eigen/Dense>  // Cholesky, QR, SVD, Eigenvalues

extern template class Eigen::JacobiSVD<Eigen::MatrixXd>;
extern template class Eigen::HouseholderQR<Eigen::MatrixXd>;
extern template class Eigen::ColPivHouseholderQR<Eigen::MatrixXd>;
extern template class Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>;
extern template class Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>;
extern template class Eigen::LDLT<Eigen::MatrixXd>;
extern template class Eigen::LLT<Eigen::MatrixXd>;
