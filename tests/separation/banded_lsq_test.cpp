// The separation's banded least-squares solver against a dense least-squares solve of the same
// rows (Eigen, column-pivoted Householder QR): solution, residual, diag((AᵀA)⁻¹) and (AᵀA)⁻¹V,
// for layouts that take each of its paths: narrow windows (width fixed at compile time, one-byte
// rotation masks), a 14-column window (two-byte masks, width at run time) and one over 64
// columns (every rotation kept), with an angle channel and with a known zero difference; each
// factorised as one chain and as two chains joined in the middle (as long runs are).
#include "../../src/separation/banded_lsq.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

using namespace trueaxis::separation::detail;

namespace {

// Both solves are backward stable on chains of a few hundred stations: they agree to round-off
// times a modest condition number.
constexpr double kAgree = 1e-9;

struct Layout {
  const char* name;
  std::vector<long> p;  // offsets in steps
  bool angle = false;
  std::optional<double> zero_difference;
  long n = 240;  // stations
};

struct Dense {
  Eigen::MatrixXd A;
  Eigen::VectorXd b;
  std::vector<int> col;  // free unknown id -> dense column (-1 pinned)
};

Dense dense_rows(const Design& D, const Eigen::MatrixXd& readings, const Eigen::VectorXd& angle) {
  Dense d;
  d.col.assign(static_cast<std::size_t>(D.nvars), -1);
  int nf = 0;
  for (int id = 0; id < D.nvars; ++id)
    if (!D.pinned[static_cast<std::size_t>(id)]) d.col[static_cast<std::size_t>(id)] = nf++;
  std::vector<std::pair<std::vector<std::pair<int, double>>, double>> rows;
  std::vector<double> m(static_cast<std::size_t>(D.N));
  for (long K = 0; K < D.n; ++K) {
    for (int i = 0; i < D.N; ++i) m[static_cast<std::size_t>(i)] = readings(K, i);
    station_rows(D, K, m.data(), D.angle ? angle[K] : 0.0, [&](const auto& c, double rhs) {
      rows.emplace_back(std::vector<std::pair<int, double>>(c.begin(), c.end()), rhs);
    });
  }
  d.A = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows.size()), nf);
  d.b.resize(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (const auto& [id, v] : rows[r].first)
      d.A(static_cast<Eigen::Index>(r), d.col[static_cast<std::size_t>(id)]) += v;
    d.b[static_cast<Eigen::Index>(r)] = rows[r].second;
  }
  return d;
}

}  // namespace

TEST(BandedLsq, EqualsADenseLeastSquaresSolve) {
  const std::vector<Layout> layouts = {
      {"three probes 0, 1, 2", {0, 1, 2}, false, {}},
      {"two probes and an angle channel", {0, 1}, true, {}},
      {"two probes, no pitch (one local unknown per station)", {0, 1}, false, {}},
      {"three probes, known zero difference", {0, 1, 2}, false, 0.002},
      {"three probes and an angle channel (5-column window)", {0, 1, 2}, true, {}},
      {"four probes 0, 1, 2, 3 (6-column window)", {0, 1, 2, 3}, false, {}},
      {"five probes", {0, 1, 2, 3, 4}, false, {}},
      {"four probes over 11 steps (14-column window)", {0, 3, 7, 11}, false, {}},
      {"four probes over 66 steps (window over 64 columns)", {0, 1, 2, 66}, false, {}, 300},
      {"three probes over 66 steps and an angle channel", {0, 1, 66}, true, {}, 300},
  };
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1e-3);
  for (const Layout& layout : layouts)
    for (const bool split : {false, true}) {
      const Layout& L = layout;
      SCOPED_TRACE(split ? "two chains" : "one chain");
      const long n = L.n;
      const double wa = 0.7;
      const Design D = make_design(L.p, n, L.angle, L.zero_difference, wa);
      Eigen::MatrixXd readings(n, D.N);
      for (Eigen::Index i = 0; i < readings.size(); ++i) readings.data()[i] = noise(rng);
      Eigen::VectorXd angle(L.angle ? n : 0);
      for (Eigen::Index i = 0; i < angle.size(); ++i) angle[i] = noise(rng);
      // The solver's angle rows carry wa·angle; station_rows scales the reading itself.
      const Eigen::VectorXd angle_mm = angle;

      BandedLsq engine(D, split ? 0 : n + 1);
      ASSERT_EQ(engine.split(), split) << L.name;
      // The first pass starts from the pins alone: every free unknown must be written (NaN
      // would remain otherwise).
      Eigen::VectorXd v = Eigen::VectorXd::Constant(D.nvars, std::nan(""));
      for (const auto& [id, value] : D.pins) v[id] = value;
      const Unknowns u = Unknowns::in(D, v);
      const Eigen::RowVectorXd mu = Eigen::RowVectorXd::Zero(D.N);
      engine.factor(readings, mu, angle_mm, u, true);
      const double ssr = engine.ssr();
      engine.solve_add(u, true);
      ASSERT_TRUE(v.allFinite()) << L.name;
      // One refinement pass through the kept rotations (or a new factorisation).
      engine.refactor_rhs(readings, mu, angle_mm, u);
      const BandedLsq::Update second = engine.solve_add(u);

      const Dense d = dense_rows(D, readings, angle);
      const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(d.A);
      ASSERT_EQ(qr.rank(), d.A.cols()) << L.name;
      const Eigen::VectorXd x = qr.solve(d.b);
      const double scale = x.cwiseAbs().maxCoeff();
      double worst = 0;
      for (int id = 0; id < D.nvars; ++id) {
        const int c = d.col[static_cast<std::size_t>(id)];
        if (c >= 0) worst = std::max(worst, std::abs(v[id] - x[c]));
      }
      EXPECT_LT(worst, kAgree * scale) << L.name;
      EXPECT_LT(second.max_correction, kAgree * scale) << L.name;
      const double ssr_dense = (d.A * x - d.b).squaredNorm();
      EXPECT_NEAR(ssr, ssr_dense, kAgree * std::max(1e-12, ssr_dense)) << L.name;

      // (AᵀA)⁻¹ = P·R⁻¹R⁻ᵀ·Pᵀ from the dense QR AP = QR: the diagonal at column P(i) is the
      // squared norm of R⁻¹'s row i.
      const Eigen::Index nf = d.A.cols();
      const Eigen::MatrixXd Rinv = qr.matrixQR().topRows(nf).triangularView<Eigen::Upper>().solve(
          Eigen::MatrixXd::Identity(nf, nf));
      Eigen::VectorXd zd(nf);
      for (Eigen::Index i = 0; i < nf; ++i)
        zd[qr.colsPermutation().indices()[i]] = Rinv.row(i).squaredNorm();

      // (AᵀA)⁻¹V for a V of three columns given row by row, and diag((AᵀA)⁻¹) by the selected
      // inversion, against the dense products; each free unknown's row arrives exactly once.
      Eigen::MatrixXd V(nf, 3);
      for (Eigen::Index i = 0; i < V.size(); ++i) V.data()[i] = noise(rng);
      Eigen::MatrixXd Zr = Eigen::MatrixXd::Zero(nf, nf);  // R⁻¹R⁻ᵀ in pivoted order
      Zr.noalias() = Rinv * Rinv.transpose();
      const auto& perm = qr.colsPermutation().indices();
      Eigen::MatrixXd Vp(nf, 3);  // Pᵀ·V
      for (Eigen::Index i = 0; i < nf; ++i) Vp.row(i) = V.row(perm[i]);
      const Eigen::MatrixXd ZVp = Zr * Vp;
      Eigen::MatrixXd ZV(nf, 3);
      for (Eigen::Index i = 0; i < nf; ++i) ZV.row(perm[i]) = ZVp.row(i);
      Eigen::MatrixXd got = Eigen::MatrixXd::Constant(nf, 3, std::nan(""));
      Eigen::VectorXd got_diag = Eigen::VectorXd::Constant(nf, std::nan(""));
      std::vector<int> seen(static_cast<std::size_t>(nf), 0);
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> gram = Eigen::Matrix3d::Constant(1.0);
      // The same callables for both solves below, so that the pass is compiled once (each
      // callable type is an instantiation of it): `use` writes into `into`, and counts the rows
      // of the first solve.
      auto v_row = [&](int id, double* out) {
        for (int j = 0; j < 3; ++j) out[j] = V(d.col[static_cast<std::size_t>(id)], j);
      };
      Eigen::MatrixXd* into = &got;
      bool first = true;
      auto use = [&](int id, const double* zv, double z) {
        const int c = d.col[static_cast<std::size_t>(id)];
        ASSERT_GE(c, 0) << L.name << ": a pinned unknown's row";
        for (int j = 0; j < 3; ++j) (*into)(c, j) = zv[j];
        if (!first) return;
        ++seen[static_cast<std::size_t>(c)];
        got_diag[c] = z;
      };
      auto ready = [] {};
      engine.solve_normal_rows<3>(v_row, use, gram.data(), ready);
      EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), nf) << L.name;
      EXPECT_LT((got - ZV).cwiseAbs().maxCoeff(), kAgree * ZV.cwiseAbs().maxCoeff()) << L.name;
      EXPECT_LT((got_diag - zd).cwiseAbs().maxCoeff(), kAgree * zd.maxCoeff()) << L.name;
      // The same with the guide and pitch rows' share of VᵀV given as sums (the forward solve
      // then sums only the workpiece rows): the same VᵀZV, and the same rows.
      std::array<double, 27> local_vv{};
      auto row_of = [&](int id) -> Eigen::RowVector3d {
        const int c = d.col[static_cast<std::size_t>(id)];
        return c >= 0 ? Eigen::RowVector3d(V.row(c)) : Eigen::RowVector3d::Zero();
      };
      for (long K = 0; K < n; ++K) {
        const Eigen::RowVector3d vg = row_of(D.g(K));
        const Eigen::RowVector3d vt = D.pitch ? row_of(D.t(K)) : Eigen::RowVector3d::Zero();
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b) {
            local_vv[static_cast<std::size_t>(a * 3 + b)] += vg[a] * vg[b];
            local_vv[static_cast<std::size_t>(9 + a * 3 + b)] += vg[a] * vt[b];
            local_vv[static_cast<std::size_t>(18 + a * 3 + b)] += vt[a] * vt[b];
          }
      }
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> gram_given = Eigen::Matrix3d::Zero();
      Eigen::MatrixXd got_given = Eigen::MatrixXd::Constant(nf, 3, std::nan(""));
      into = &got_given;
      first = false;
      engine.solve_normal_rows<3>(v_row, use, gram_given.data(), ready, local_vv.data());
      EXPECT_LT((got_given - ZV).cwiseAbs().maxCoeff(), kAgree * ZV.cwiseAbs().maxCoeff())
          << L.name;
      // The solve took the kept rotations' memory: a further refinement factorises again.
      engine.refactor_rhs(readings, mu, angle_mm, u);
      EXPECT_LT(engine.solve_add(u).max_correction, kAgree * scale) << L.name;
      // VᵀZV from the forward rows, added to what the matrix held (ones).
      const Eigen::Matrix3d VZV = V.transpose() * ZV;
      EXPECT_LT((gram - Eigen::Matrix3d::Constant(1.0) - VZV).cwiseAbs().maxCoeff(),
                kAgree * VZV.cwiseAbs().maxCoeff())
          << L.name;
      EXPECT_LT((gram_given - VZV).cwiseAbs().maxCoeff(), kAgree * VZV.cwiseAbs().maxCoeff())
          << L.name;
    }
}
