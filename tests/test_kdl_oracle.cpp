// The generated regressors and dynamics against orocos-kdl's recursive Newton-Euler and mass
// matrix, for random states and random physically consistent parameters.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <fstream>
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <nlohmann/json.hpp>
#include <random>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/generated/tx40/robot.hpp"
#include "support/random_physical.hpp"
#include "support/test_paths.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace kdl_oracle_suite {

using dyncal::test::Body;

KDL::RigidBodyInertia kdl_inertia(const Body& b) {
  return KDL::RigidBodyInertia(
      b.m, KDL::Vector(b.c.x(), b.c.y(), b.c.z()),
      KDL::RotationalInertia(b.Ic(0, 0), b.Ic(1, 1), b.Ic(2, 2), b.Ic(0, 1), b.Ic(0, 2), b.Ic(1, 2)));
}

// Chain from the generated joint origins: joint i rotates about R_i z through p_i (parent frame),
// and its tip frame is link i's frame.
template <class Origins>
KDL::Chain chain_from_origins(const Origins& origins, const std::vector<Body>& bodies) {
  KDL::Chain chain;
  for (size_t i = 0; i < bodies.size(); ++i) {
    const auto& o = origins[i];
    const KDL::Rotation R(o.R[0], o.R[1], o.R[2], o.R[3], o.R[4], o.R[5], o.R[6], o.R[7], o.R[8]);
    const KDL::Vector p(o.p[0], o.p[1], o.p[2]);
    const KDL::Joint joint("j", p, R * KDL::Vector(0, 0, 1), KDL::Joint::RotAxis);
    chain.addSegment(KDL::Segment(joint, KDL::Frame(R, p), kdl_inertia(bodies[i])));
  }
  return chain;
}

// Chain built independently from robots/er20/robot.json with KDL's own modified-DH frames.
KDL::Chain er20_chain_from_mdh(const std::vector<Body>& bodies) {
  std::ifstream in(std::string(dyncal::test::source_dir()) + "/robots/er20/robot.json");
  const auto desc = nlohmann::json::parse(in);
  KDL::Chain chain;
  for (size_t i = 0; i < bodies.size(); ++i) {
    const auto& j = desc["kinematics"]["joints"][i];
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::None),
                                  KDL::Frame::DH_Craig1989(j["a"].get<double>(), j["alpha"].get<double>(),
                                                           j["d"].get<double>(), j["theta"].get<double>())));
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::RotZ), KDL::Frame::Identity(), kdl_inertia(bodies[i])));
  }
  return chain;
}

template <class Robot, class Origins>
void check_against_kdl(const Origins& origins, bool also_mdh) {
  constexpr int N = Robot::kNumJoints;
  using Vec = Eigen::Matrix<double, N, 1>;
  using Phi = Eigen::Matrix<double, Robot::kNumStandard, 1>;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const KDL::Vector gravity(Robot::gravity(0), Robot::gravity(1), Robot::gravity(2));
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Body> bodies;
    Phi phi;
    for (int k = 0; k < N; ++k) {
      bodies.push_back(dyncal::test::random_body(rng));
      phi.template segment<10>(10 * k) = dyncal::test::standard_parameters(bodies.back());
    }
    Vec q, qd, qdd;
    for (int i = 0; i < N; ++i) {
      q[i] = 3.0 * u(rng);
      qd[i] = 2.0 * u(rng);
      qdd[i] = 5.0 * u(rng);
    }
    KDL::JntArray kq(N), kqd(N), kqdd(N), ktau(N);
    for (int i = 0; i < N; ++i) {
      kq(i) = q[i];
      kqd(i) = qd[i];
      kqdd(i) = qdd[i];
    }
    std::vector<KDL::Chain> chains{chain_from_origins(origins, bodies)};
    if (also_mdh) chains.push_back(er20_chain_from_mdh(bodies));
    Eigen::Matrix<double, N, Robot::kNumStandard> Y;
    Robot::standard_regressor(q, qd, qdd, Y);
    const Vec tau_regressor = Y * phi;
    Vec tau_id;
    Robot::inverse_dynamics(q, qd, qdd, phi, tau_id);
    Eigen::Matrix<double, N, N> M;
    Robot::mass_matrix(q, phi, M);
    for (const auto& chain : chains) {
      KDL::ChainIdSolver_RNE rne(chain, gravity);
      KDL::Wrenches fext(chain.getNrOfSegments(), KDL::Wrench::Zero());
      ASSERT_GE(rne.CartToJnt(kq, kqd, kqdd, fext, ktau), 0);
      Vec tau_kdl;
      for (int i = 0; i < N; ++i) tau_kdl[i] = ktau(i);
      const double scale = std::max(1.0, tau_kdl.cwiseAbs().maxCoeff());
      EXPECT_LE((tau_regressor - tau_kdl).cwiseAbs().maxCoeff(), 1e-9 * scale) << "trial " << trial;
      EXPECT_LE((tau_id - tau_kdl).cwiseAbs().maxCoeff(), 1e-9 * scale) << "trial " << trial;
      KDL::ChainDynParam dyn(chain, KDL::Vector::Zero());
      KDL::JntSpaceInertiaMatrix H(N);
      ASSERT_GE(dyn.JntToMass(kq, H), 0);
      // Read through KDL's accessor, never through H.data: Debian builds orocos-kdl for baseline
      // x86-64, so its Eigen storage is 16-byte aligned, and this unit's Eigen (AVX) assumes 32.
      Eigen::Matrix<double, N, N> M_kdl;
      for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) M_kdl(i, j) = H(static_cast<unsigned>(i), static_cast<unsigned>(j));
      const double mscale = std::max(1.0, M_kdl.cwiseAbs().maxCoeff());
      EXPECT_LE((M - M_kdl).cwiseAbs().maxCoeff(), 1e-9 * mscale) << "trial " << trial;
    }
    // Base regressor times base parameters reproduces the standard torque.
    Eigen::Matrix<double, N, Robot::kNumBase> Yb;
    Robot::base_regressor(q, qd, qdd, Yb);
    Eigen::Matrix<double, Robot::kNumBase, 1> phi_b;
    Robot::standard_to_base(phi, phi_b);
    const Vec tau_base = Yb * phi_b;
    EXPECT_LE((tau_base - tau_regressor).cwiseAbs().maxCoeff(),
              1e-9 * std::max(1.0, tau_regressor.cwiseAbs().maxCoeff()));
  }
}

TEST(KdlOracle, Er20MatchesKdlFromGeneratedOriginsAndFromMdh) {
  check_against_kdl<dyncal::generated::er20::Robot>(dyncal::generated::er20::kJointOrigins, true);
}

TEST(KdlOracle, Tx40MatchesKdl) {
  check_against_kdl<dyncal::generated::tx40::Robot>(dyncal::generated::tx40::kJointOrigins, false);
}

TEST(KdlOracle, BaseParametersAreFewerAndTheMapDropsNoEffect) {
  // A parameter change along an unidentifiable direction (link 1's XX) changes no torque and no
  // base parameter.
  using Robot = dyncal::generated::er20::Robot;
  Eigen::Matrix<double, Robot::kNumStandard, 1> phi = Eigen::Matrix<double, Robot::kNumStandard, 1>::Zero();
  Eigen::Matrix<double, Robot::kNumBase, 1> b0, b1;
  Robot::standard_to_base(phi, b0);
  phi[static_cast<int>(dyncal::generated::er20::StandardParam::link1_XX)] = 3.0;
  Robot::standard_to_base(phi, b1);
  EXPECT_EQ((b1 - b0).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT(Robot::kNumBase, Robot::kNumStandard);
}

}  // namespace kdl_oracle_suite
}  // namespace
