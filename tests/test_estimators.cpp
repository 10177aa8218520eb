// lib/ estimators against batch references on exact synthetic er20 data.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <memory>
#include <random>

#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "dyncal/ud_covariance.hpp"
#include "support/synthetic.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace estimators_suite {

using dyncal::UpdateStatus;
using dyncal::test::Er20;
constexpr unsigned kTerms = dyncal::kFrictionEq7 | dyncal::term::offset;
using Model = dyncal::IdentificationModel<Er20, kTerms>;
constexpr int P = Model::kNumParams;
constexpr int N = 6;
using ParamVec = Eigen::Matrix<double, P, 1>;
using JointVec = Eigen::Matrix<double, N, 1>;
const JointVec kZero = JointVec::Zero();

struct Samples {
  std::vector<Eigen::Matrix<double, N, P>> K;
  std::vector<JointVec> tau;
};

Samples make_samples(int count, double dt, const ParamVec& phi, double noise = 0.0, unsigned seed = 1) {
  Samples s;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  JointVec q, qd, qdd;
  for (int i = 0; i < count; ++i) {
    dyncal::test::fourier_state(i * dt, q, qd, qdd);
    Eigen::Matrix<double, N, P> K;
    Model::regressor(q, qd, qdd, kZero, K);
    JointVec tau = K * phi;
    for (int j = 0; j < N; ++j) tau[j] += noise * gauss(rng);
    s.K.push_back(K);
    s.tau.push_back(tau);
  }
  return s;
}

TEST(StreamingLeastSquares, EqualsDenseQrSolve) {
  const ParamVec truth = dyncal::test::er20_truth<kTerms>();
  const Samples s = make_samples(2000, 0.01, truth, 1.0);
  auto ls = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  Eigen::MatrixXd W(2000 * N, P);
  Eigen::VectorXd y(2000 * N);
  for (size_t i = 0; i < s.K.size(); ++i) {
    ASSERT_EQ(ls->update(s.K[i], s.tau[i]), UpdateStatus::ok);
    W.middleRows(static_cast<Eigen::Index>(i) * N, N) = s.K[i];
    y.segment(static_cast<Eigen::Index>(i) * N, N) = s.tau[i];
  }
  ParamVec phi;
  ASSERT_EQ(ls->solve(phi), UpdateStatus::ok);
  const Eigen::VectorXd dense = W.colPivHouseholderQr().solve(y);
  EXPECT_LE((phi - dense).norm(), 1e-9 * dense.norm());
  const double rss = (y - W * dense).squaredNorm();
  EXPECT_NEAR(ls->residual_sum_of_squares(), rss, 1e-9 * rss);
}

TEST(StreamingLeastSquares, MergeEqualsSingleAccumulator) {
  const Samples s = make_samples(600, 0.02, dyncal::test::er20_truth<kTerms>(), 0.5);
  auto all = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  auto a = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  auto b = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  for (size_t i = 0; i < s.K.size(); ++i) {
    all->update(s.K[i], s.tau[i]);
    (i % 3 == 0 ? *a : *b).update(s.K[i], s.tau[i]);
  }
  ASSERT_EQ(a->merge(*b), UpdateStatus::ok);
  ParamVec p1, p2;
  ASSERT_EQ(all->solve(p1), UpdateStatus::ok);
  ASSERT_EQ(a->solve(p2), UpdateStatus::ok);
  EXPECT_LE((p1 - p2).norm(), 1e-9 * p1.norm());
  EXPECT_NEAR(a->residual_sum_of_squares(), all->residual_sum_of_squares(), 1e-9 * all->residual_sum_of_squares());
}

// A column whose first rows hold only a low-pass's tail (about 1e-170, before its signal starts)
// squares to 0 against an empty R: the rotation must not become 0 / 0 (identify's shapes of time
// times the friction sign met it). The solution equals the dense QR's.
TEST(StreamingLeastSquares, TinyEntriesAheadOfAColumnLeaveNoNaN) {
  constexpr int M = 3;
  dyncal::StreamingLeastSquares<double, M> ls;
  std::mt19937 rng(5);
  std::normal_distribution<double> gauss;
  const int rows = 400;
  Eigen::MatrixXd W(rows, M);
  Eigen::VectorXd y(rows);
  for (int i = 0; i < rows; ++i) {
    W(i, 0) = gauss(rng);
    W(i, 1) = i < rows / 2 ? 1e-170 * std::exp(-0.1 * (rows / 2 - i)) : gauss(rng);
    W(i, 2) = i < rows / 4 ? 0.0 : gauss(rng);
    y[i] = W.row(i).dot(Eigen::Vector3d(1.0, -2.0, 0.5)) + 0.01 * gauss(rng);
    ASSERT_EQ(ls.add_row(Eigen::Vector3d(W.row(i).transpose()), y[i]), UpdateStatus::ok);
  }
  Eigen::Matrix<double, M, 1> phi;
  ASSERT_EQ(ls.solve(phi), UpdateStatus::ok);
  ASSERT_TRUE(phi.allFinite());
  const Eigen::VectorXd dense = W.colPivHouseholderQr().solve(y);
  EXPECT_LE((phi - dense).norm(), 1e-9 * dense.norm());
}

TEST(StreamingLeastSquares, RejectsNonFiniteAndReportsRankDeficiency) {
  auto ls = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  ParamVec phi = ParamVec::Constant(7.0);
  EXPECT_EQ(ls->solve(phi), UpdateStatus::rank_deficient);
  EXPECT_EQ(phi[0], 7.0);
  Eigen::Matrix<double, N, P> K = Eigen::Matrix<double, N, P>::Ones();
  JointVec tau = JointVec::Ones();
  tau[2] = std::nan("");
  EXPECT_EQ(ls->update(K, tau), UpdateStatus::rejected_non_finite);
  EXPECT_EQ(ls->rows(), 0);
}

TEST(KalmanFilter, ConvergesToBatchOlsOnNoiseFreeData) {
  const ParamVec truth = dyncal::test::er20_truth<kTerms>();
  const Samples s = make_samples(3000, 0.01, truth);
  auto kf = std::make_unique<dyncal::KalmanFilter<double, P, N>>();
  ASSERT_EQ(kf->reset(ParamVec::Zero(), ParamVec::Constant(1e8)), UpdateStatus::ok);
  auto ls = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  for (size_t i = 0; i < s.K.size(); ++i) {
    ASSERT_EQ(kf->update(s.K[i], s.tau[i], JointVec::Ones()), UpdateStatus::ok);
    ls->update(s.K[i], s.tau[i]);
  }
  ParamVec ols;
  ASSERT_EQ(ls->solve(ols), UpdateStatus::ok);
  EXPECT_LE((ols - truth).norm(), 1e-8 * truth.norm());
  EXPECT_LE((kf->estimate() - ols).norm(), 1e-5 * ols.norm());
  // The prior covariance P0 is the only difference; it vanishes as P0 grows.
  Eigen::Matrix<double, P, P> Pd;
  kf->covariance().to_dense(Pd);
  EXPECT_LE((Pd - Pd.transpose()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Pd).eigenvalues().minCoeff(), 0.0);
}

TEST(KalmanFilter, NonFiniteAndOutlierSamplesLeaveStateUntouched) {
  const ParamVec truth = dyncal::test::er20_truth<kTerms>();
  const Samples s = make_samples(500, 0.01, truth, 0.1);
  auto kf = std::make_unique<dyncal::KalmanFilter<double, P, N>>();
  ASSERT_EQ(kf->reset(ParamVec::Zero(), ParamVec::Constant(1e6)), UpdateStatus::ok);
  for (size_t i = 0; i < s.K.size(); ++i)
    ASSERT_EQ(kf->update(s.K[i], s.tau[i], JointVec::Constant(0.01)), UpdateStatus::ok);
  ASSERT_EQ(kf->set_gate(5.0), UpdateStatus::ok);
  const ParamVec before = kf->estimate();
  Eigen::Matrix<double, P, P> p_before, p_after;
  kf->covariance().to_dense(p_before);
  JointVec bad = s.tau[10];
  bad[3] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(kf->update(s.K[10], bad, JointVec::Constant(0.01)), UpdateStatus::rejected_non_finite);
  JointVec outlier = s.tau[10];
  outlier[1] += 1000.0;
  EXPECT_EQ(kf->update(s.K[10], outlier, JointVec::Constant(0.01)), UpdateStatus::rejected_outlier);
  EXPECT_EQ(kf->update(s.K[10], s.tau[10], JointVec::Zero()), UpdateStatus::not_positive_definite);
  EXPECT_EQ((kf->estimate() - before).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((kf->estimate() - before).cwiseAbs().maxCoeff(), 0.0);
  kf->covariance().to_dense(p_after);
  EXPECT_EQ((p_after - p_before).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(kf->update(s.K[10], s.tau[10], JointVec::Constant(0.01)), UpdateStatus::ok);
}

// The block update over packed P with the regressor's structure must equal N sequential scalar
// Bierman updates on a UD-factorised P (an independent implementation of Eq. 19).
TEST(KalmanFilter, StructuredBlockUpdateEqualsSequentialBiermanUpdates) {
  const ParamVec truth = dyncal::test::er20_truth<kTerms>();
  const Samples s = make_samples(400, 0.01, truth, 0.5);
  auto kf = std::make_unique<dyncal::KalmanFilter<double, P, N>>();
  ASSERT_EQ(kf->reset(ParamVec::Zero(), ParamVec::Constant(1e4), Model::structure()), UpdateStatus::ok);
  auto ud = std::make_unique<dyncal::UdCovariance<double, P>>();
  ASSERT_EQ(ud->reset(ParamVec::Constant(1e4)), UpdateStatus::ok);
  ParamVec phi_ud = ParamVec::Zero();
  const JointVec r(0.01, 0.02, 0.03, 0.04, 0.05, 0.06);
  for (size_t i = 0; i < s.K.size(); ++i) {
    ASSERT_EQ(kf->update(s.K[i], s.tau[i], r), UpdateStatus::ok);
    for (int j = 0; j < N; ++j) {
      const ParamVec h = s.K[i].row(j).transpose();
      ASSERT_EQ(ud->assimilate(h, s.tau[i][j], r[j], phi_ud), UpdateStatus::ok);
    }
  }
  EXPECT_LE((kf->estimate() - phi_ud).norm(), 1e-8 * phi_ud.norm());
  Eigen::Matrix<double, P, P> p_kf, p_ud;
  kf->covariance().to_dense(p_kf);
  ud->to_dense(p_ud);
  // The covariance form subtracts from the prior (1e4): its rounding is relative to that scale.
  EXPECT_LE((p_kf - p_ud).cwiseAbs().maxCoeff(), 1e-11 * 1e4);
}

TEST(KalmanFilter, RegressorOutsideItsStructureIsRejected) {
  const ParamVec truth = dyncal::test::er20_truth<kTerms>();
  const Samples s = make_samples(10, 0.01, truth);
  auto kf = std::make_unique<dyncal::KalmanFilter<double, P, N>>();
  ASSERT_EQ(kf->reset(ParamVec::Zero(), ParamVec::Constant(1e4), Model::structure()), UpdateStatus::ok);
  Eigen::Matrix<double, N, P> K = s.K[3];
  K(5, 0) = 1.0;  // base column 0 (link1_ZZ_R) acts on joint 1 only
  EXPECT_EQ(kf->update(K, s.tau[3], JointVec::Ones()), UpdateStatus::invalid_argument);
  K(5, 0) = std::nan("");
  EXPECT_EQ(kf->update(K, s.tau[3], JointVec::Ones()), UpdateStatus::rejected_non_finite);
  EXPECT_EQ(kf->estimate().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(kf->update(s.K[3], s.tau[3], JointVec::Ones()), UpdateStatus::ok);
}

// The float update (4-row blocks of V, the trailing term block in one pass) with a column the
// structure declares all zero: it must follow the double run of the same data, and a nonzero entry
// in that column must be refused.
TEST(KalmanFilter, FloatBlockUpdateWithZeroColumnFollowsDouble) {
  const ParamVec truth = dyncal::test::er20_truth<kTerms>();
  const Samples s = make_samples(300, 0.01, truth, 1.0);
  dyncal::RegressorStructure<P> structure = Model::structure();
  structure.first[0] = 1;  // column 0 declared all zero (and zeroed below)
  structure.last[0] = 0;
  using ParamVecF = Eigen::Matrix<float, P, 1>;
  auto kf_f = std::make_unique<dyncal::KalmanFilter<float, P, N>>();
  auto kf_d = std::make_unique<dyncal::KalmanFilter<double, P, N>>();
  ASSERT_EQ(kf_f->reset(ParamVecF::Zero(), ParamVecF::Constant(1e4f), structure), UpdateStatus::ok);
  ASSERT_EQ(kf_d->reset(ParamVec::Zero(), ParamVec::Constant(1e4), structure), UpdateStatus::ok);
  const JointVec r = JointVec::Ones();
  for (size_t i = 0; i < s.K.size(); ++i) {
    Eigen::Matrix<double, N, P> K = s.K[i];
    K.col(0).setZero();
    ASSERT_EQ(kf_d->update(K, s.tau[i], r), UpdateStatus::ok);
    ASSERT_EQ(kf_f->update(K.cast<float>(), s.tau[i].cast<float>(), r.cast<float>()), UpdateStatus::ok);
  }
  // Torque predicted over the samples by the float and the double estimate. Float carries ~7 digits,
  // but the covariance form loses them in proportion to the prior/posterior variance ratio (1e4 to
  // ~1e-2 here): measured 1.46e-3 with -march=native on an AMD EPYC (znver4 code), below 1e-3 on the
  // Intel host of earlier runs; the bound leaves room for the instruction selection of either.
  double diff = 0, norm = 0;
  for (size_t i = 0; i < s.K.size(); ++i) {
    const JointVec t_d = s.K[i] * kf_d->estimate();
    const JointVec t_f = s.K[i] * kf_f->estimate().cast<double>();
    diff += (t_f - t_d).squaredNorm();
    norm += t_d.squaredNorm();
  }
  EXPECT_LT(std::sqrt(diff / norm), 3e-3);
  Eigen::Matrix<float, N, P> K = s.K[5].cast<float>();
  K(2, 0) = 1.0f;
  const ParamVecF before = kf_f->estimate();
  EXPECT_EQ(kf_f->update(K, s.tau[5].cast<float>(), r.cast<float>()), UpdateStatus::invalid_argument);
  EXPECT_EQ(kf_f->estimate(), before);
}

// Survey Fig. 4: beta of joint 3 changes as a ramp or as a second-order function of the
// iteration; forgetting RLS must track it more closely than the Kalman filter.
double tracking_error(bool use_rls, bool second_order) {
  const ParamVec truth = dyncal::test::er20_truth<kTerms>();
  const int beta3 = Model::column(dyncal::term::viscous, 2);
  const int count = 6000;
  auto kf = std::make_unique<dyncal::KalmanFilter<double, P, N>>();
  auto rls = std::make_unique<dyncal::RlsForgetting<double, P, N>>();
  kf->reset(ParamVec::Zero(), ParamVec::Constant(1e6));
  rls->reset(ParamVec::Zero(), ParamVec::Constant(1e6), 0.995);
  JointVec q, qd, qdd;
  double se = 0.0;
  int n = 0;
  for (int i = 0; i < count; ++i) {
    const double x = static_cast<double>(i) / count;
    ParamVec phi = truth;
    phi[beta3] = truth[beta3] * (second_order ? 1.0 + 0.5 * x * x : 1.0 + 0.5 * x);
    dyncal::test::fourier_state(i * 0.01, q, qd, qdd);
    Eigen::Matrix<double, N, P> K;
    Model::regressor(q, qd, qdd, kZero, K);
    const JointVec tau = K * phi;
    const UpdateStatus st = use_rls ? rls->update(K, tau) : kf->update(K, tau, JointVec::Ones());
    EXPECT_EQ(st, UpdateStatus::ok);
    if (i >= count / 2) {
      const double e = (use_rls ? rls->estimate() : kf->estimate())[beta3] - phi[beta3];
      se += e * e;
      ++n;
    }
  }
  return std::sqrt(se / n);
}

TEST(RlsForgetting, TracksRampBetterThanKalman) {
  const double kf = tracking_error(false, false), rls = tracking_error(true, false);
  EXPECT_LT(rls, kf);
  EXPECT_LT(rls, 0.25 * kf);
}

TEST(RlsForgetting, TracksSecondOrderChangeBetterThanKalman) {
  const double kf = tracking_error(false, true), rls = tracking_error(true, true);
  EXPECT_LT(rls, kf);
  EXPECT_LT(rls, 0.25 * kf);
}

TEST(RlsForgetting, CovarianceStaysBoundedWithoutExcitation) {
  auto rls = std::make_unique<dyncal::RlsForgetting<double, P, N>>();
  ASSERT_EQ(rls->reset(ParamVec::Zero(), ParamVec::Constant(1.0), 0.98), UpdateStatus::ok);
  const double trace0 = rls->covariance().trace();
  Eigen::Matrix<double, N, P> K = Eigen::Matrix<double, N, P>::Zero();  // no excitation at all
  for (int i = 0; i < 5000; ++i) ASSERT_EQ(rls->update(K, JointVec::Zero()), UpdateStatus::ok);
  EXPECT_LE(rls->covariance().trace(), trace0 / 0.98 + 1e-9);
  EXPECT_EQ(rls->update(K, JointVec::Zero(), JointVec::Zero()), UpdateStatus::invalid_argument);
}

// The run-time size (P = Eigen::Dynamic, capacity MaxP: the host's one instantiation per N) runs
// the same arithmetic as the fixed size: KF and RLS estimates and covariances equal bit for bit,
// with the model's structure (runs, zero columns, the friction block) and with noise.
TEST(RuntimeSize, KalmanAndRlsEqualFixedSizeBitForBit) {
  constexpr int kCap = 15 * N;  // 10 N standard + 5 N term columns: any model of N joints
  using DynCov = dyncal::PackedCovariance<double, Eigen::Dynamic, N, kCap>;
  using DynKf = dyncal::KalmanFilter<double, Eigen::Dynamic, N, DynCov>;
  using DynRls = dyncal::RlsForgetting<double, Eigen::Dynamic, N, DynCov>;
  const Samples s = make_samples(400, 0.01, dyncal::test::er20_truth<kTerms>(), 0.5);
  const auto fixed_structure = Model::structure();
  DynKf::Structure structure = DynKf::Structure::dense(N);
  for (int c = 0; c < P; ++c) {
    structure.first[c] = fixed_structure.first[c];
    structure.last[c] = fixed_structure.last[c];
  }
  auto kf = std::make_unique<dyncal::KalmanFilter<double, P, N>>();
  auto rls = std::make_unique<dyncal::RlsForgetting<double, P, N>>();
  auto dkf = std::make_unique<DynKf>();
  auto drls = std::make_unique<DynRls>();
  const ParamVec p0 = ParamVec::Constant(1e4);
  ASSERT_EQ(kf->reset(ParamVec::Zero(), p0, fixed_structure), UpdateStatus::ok);
  ASSERT_EQ(rls->reset(ParamVec::Zero(), p0, 0.99, 0.0, fixed_structure), UpdateStatus::ok);
  const DynKf::ParamVector dp0 = p0, dzero = ParamVec::Zero();
  ASSERT_EQ(dkf->reset(dzero, dp0, structure), UpdateStatus::ok);
  ASSERT_EQ(drls->reset(dzero, dp0, 0.99, 0.0, structure), UpdateStatus::ok);
  ASSERT_EQ(dkf->estimate().size(), P);
  for (size_t i = 0; i < s.K.size(); ++i) {
    const DynKf::Regressor K = s.K[i];
    ASSERT_EQ(dkf->update(K, s.tau[i], JointVec::Ones()), kf->update(s.K[i], s.tau[i], JointVec::Ones()));
    ASSERT_EQ(drls->update(K, s.tau[i]), rls->update(s.K[i], s.tau[i]));
  }
  for (int c = 0; c < P; ++c) {
    EXPECT_EQ(dkf->estimate()[c], kf->estimate()[c]) << c;
    EXPECT_EQ(drls->estimate()[c], rls->estimate()[c]) << c;
    for (int d = 0; d < P; ++d) {
      EXPECT_EQ(dkf->covariance()(c, d), kf->covariance()(c, d));
      EXPECT_EQ(drls->covariance()(c, d), rls->covariance()(c, d));
    }
  }
  // No size, a bad p0, a bad structure or phi0 and p0 of different sizes are refused and change nothing:
  // the filters go on equal.
  DynKf::ParamVector none(0), bad_p0 = dp0;
  bad_p0[P - 1] = -1.0;
  // Dense (other runs than the model's) up to a last column with a row beyond the regressor's.
  DynKf::Structure bad_structure = DynKf::Structure::dense(N);
  bad_structure.last[P - 1] = N;
  EXPECT_EQ(dkf->reset(none, none, structure), UpdateStatus::invalid_argument);
  EXPECT_EQ(dkf->reset(dzero, dp0, bad_structure), UpdateStatus::invalid_argument);
  EXPECT_EQ(dkf->reset(dzero.head(P - 1), dp0, structure), UpdateStatus::invalid_argument);  // phi0, p0 sizes
  EXPECT_EQ(dkf->reset(dzero, bad_p0, structure), UpdateStatus::invalid_argument);
  EXPECT_EQ(drls->reset(dzero, dp0, 0.99, 0.0, bad_structure), UpdateStatus::invalid_argument);
  ASSERT_EQ(dkf->update(s.K[0], s.tau[0], JointVec::Ones()), kf->update(s.K[0], s.tau[0], JointVec::Ones()));
  ASSERT_EQ(drls->update(s.K[0], s.tau[0]), rls->update(s.K[0], s.tau[0]));
  for (int c = 0; c < P; ++c) {
    EXPECT_EQ(dkf->estimate()[c], kf->estimate()[c]) << c;
    EXPECT_EQ(drls->estimate()[c], rls->estimate()[c]) << c;
  }
}

// StreamingLeastSquares at the run-time size (the host's identify: one instantiation for every model)
// folds the same rows into the same R, z and residual as the fixed size, bit for bit; sizes it cannot
// take are refused and change nothing.
TEST(RuntimeSize, StreamingLeastSquaresEqualsFixedSizeBitForBit) {
  using DynLs = dyncal::StreamingLeastSquares<double, Eigen::Dynamic, 15 * N>;
  const Samples s = make_samples(400, 0.01, dyncal::test::er20_truth<kTerms>(), 0.5);
  auto ls = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  auto a = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  auto dls = std::make_unique<DynLs>();
  auto da = std::make_unique<DynLs>();
  EXPECT_EQ(dls->size(), 0);
  EXPECT_FALSE(dls->full_rank());
  EXPECT_EQ(dls->reset(0), UpdateStatus::invalid_argument);
  EXPECT_EQ(dls->reset(15 * N + 1), UpdateStatus::invalid_argument);
  EXPECT_EQ(ls->reset(P - 1), UpdateStatus::invalid_argument);  // a fixed size takes only its own
  ASSERT_EQ(ls->reset(P), UpdateStatus::ok);
  ASSERT_EQ(dls->reset(P), UpdateStatus::ok);
  ASSERT_EQ(da->reset(P), UpdateStatus::ok);
  for (size_t i = 0; i < s.K.size(); ++i) {
    const DynLs::Regressor<N> K = s.K[i];
    ASSERT_EQ(dls->update(K, s.tau[i]), ls->update(s.K[i], s.tau[i]));
    if (i % 4 == 0) {  // every 4th sample row by row, weighted, into a second pair: merged below
      for (int j = 0; j < N; ++j) {
        const double w = 1.0 + 0.1 * j;
        ASSERT_EQ(da->add_row(K.row(j).transpose(), s.tau[i][j], w), UpdateStatus::ok);
        ASSERT_EQ(a->add_row(s.K[i].row(j).transpose(), s.tau[i][j], w), UpdateStatus::ok);
      }
    }
  }
  // A row of another size is refused, as is merging accumulators of different sizes.
  const Eigen::VectorXd short_row = Eigen::VectorXd::Ones(P - 1);
  EXPECT_EQ(dls->add_row(short_row, 1.0), UpdateStatus::invalid_argument);
  DynLs other;
  ASSERT_EQ(other.reset(P - 1), UpdateStatus::ok);
  EXPECT_EQ(dls->merge(other), UpdateStatus::invalid_argument);
  ASSERT_EQ(dls->merge(*da), UpdateStatus::ok);
  ASSERT_EQ(ls->merge(*a), UpdateStatus::ok);
  ASSERT_EQ(dls->rows(), ls->rows());
  EXPECT_EQ(dls->residual_sum_of_squares(), ls->residual_sum_of_squares());
  for (int r = 0; r < P; ++r) {
    EXPECT_EQ(dls->rotated_rhs()[r], ls->rotated_rhs()[r]) << r;
    for (int c = 0; c < P; ++c) EXPECT_EQ(dls->r_factor()(r, c), ls->r_factor()(r, c)) << r << ", " << c;
  }
  ParamVec phi, diag;
  DynLs::Vector dphi, ddiag;
  ASSERT_EQ(ls->solve(phi), UpdateStatus::ok);
  ASSERT_EQ(dls->solve(dphi), UpdateStatus::ok);
  ASSERT_EQ(ls->inverse_gram_diagonal(diag), UpdateStatus::ok);
  ASSERT_EQ(dls->inverse_gram_diagonal(ddiag), UpdateStatus::ok);
  ASSERT_EQ(dphi.size(), P);
  for (int c = 0; c < P; ++c) {
    EXPECT_EQ(dphi[c], phi[c]) << c;
    EXPECT_EQ(ddiag[c], diag[c]) << c;
  }
}

}  // namespace estimators_suite
}  // namespace
