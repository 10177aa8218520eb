#pragma once
// The er20 identification model test_no_malloc's er20 files run (Eq. 8 friction, rotor inertia,
// offsets): its estimators, generated code and drive code are checked on the same model.
#include "support/synthetic.hpp"

namespace dyncal::test::no_malloc {

using dyncal::test::Er20;
inline constexpr unsigned kTerms = dyncal::kFrictionEq8 | dyncal::term::rotor_inertia | dyncal::term::offset;
using Model = dyncal::IdentificationModel<Er20, kTerms>;
inline constexpr int P = Model::kNumParams;
using JointVec = Eigen::Matrix<double, 6, 1>;

}  // namespace dyncal::test::no_malloc
