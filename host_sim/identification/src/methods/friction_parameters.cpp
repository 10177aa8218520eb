#include "dyncal_host/identification/methods/friction_parameters.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal/nonlinear_friction.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

double sgn(double v) {
  return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
}

}  // namespace

const char* model_key(FrictionModel model) {
  switch (model) {
    case FrictionModel::eq4:
      return "eq4";
    case FrictionModel::eq5:
      return "eq5";
    case FrictionModel::eq6:
      return "eq6";
    case FrictionModel::eq7:
      return "eq7";
    case FrictionModel::eq8:
      return "eq8";
    case FrictionModel::eq9:
      return "eq9";
  }
  return "?";
}

bool is_linear(FrictionModel model) {
  return model == FrictionModel::eq7 || model == FrictionModel::eq8 || model == FrictionModel::eq9;
}

std::vector<std::string> friction_parameter_names(FrictionModel model) {
  switch (model) {
    case FrictionModel::eq7:
      return {"Fc", "beta"};
    case FrictionModel::eq8:
      return {"Fc", "beta", "fp"};
    case FrictionModel::eq9:
      return {"Fc", "beta", "fl"};
    case FrictionModel::eq4:
      return {"Fc", "Fs", "qds", "beta"};
    case FrictionModel::eq5:
      return {"f1", "f2", "f3", "f4", "f5", "beta"};
    case FrictionModel::eq6:
      return {"f1", "f2", "f3", "f4", "beta"};
  }
  throw InputError("unknown friction model");
}

int friction_count(FrictionModel model) {
  switch (model) {  // friction_parameter_names(model).size(), without building the names (hot loops call it)
    case FrictionModel::eq7:
      return 2;
    case FrictionModel::eq8:
    case FrictionModel::eq9:
      return 3;
    case FrictionModel::eq4:
      return 4;
    case FrictionModel::eq5:
      return 6;
    case FrictionModel::eq6:
      return 5;
  }
  throw InputError("unknown friction model");
}

bool is_scale_parameter(FrictionModel model, int k) {
  switch (model) {
    case FrictionModel::eq4:
      return NonlinearFriction<NonlinearFrictionModel::eq4>::kIsScale[k];
    case FrictionModel::eq5:
      return NonlinearFriction<NonlinearFrictionModel::eq5>::kIsScale[k];
    case FrictionModel::eq6:
      return NonlinearFriction<NonlinearFrictionModel::eq6>::kIsScale[k];
    default:
      return false;
  }
}

bool is_inverse_velocity(FrictionModel model, int k) {
  return (model == FrictionModel::eq5 && k == 4) || (model == FrictionModel::eq6 && (k == 2 || k == 3));
}

bool is_linear_parameter(FrictionModel model, int k) {
  if (is_linear(model)) return true;
  const int beta = friction_count(model) - 1;
  if (k == beta) return true;
  return k == 0 && (model == FrictionModel::eq4 || model == FrictionModel::eq5);
}

double linear_column(FrictionModel model, int k, double qd, double tau_load) {
  if (!is_linear_parameter(model, k)) return 0.0;
  if (k == friction_count(model) - 1 && !is_linear(model)) return qd;  // beta of Eq. 4, 5, 6
  switch (k) {
    case 0:
      return sgn(qd);
    case 1:
      return qd;
    default:
      return model == FrictionModel::eq8 ? std::cbrt(qd) : std::fabs(tau_load) * sgn(qd);
  }
}

double friction_torque(FrictionModel model, const double* theta, double qd, double tau_load, double* grad) {
  if (!is_linear(model)) {
    // Scale parameters act from 1e-3 (lib/ projects qds, f3, f5 of Eq. 4, 5 and f4 of Eq. 6 there;
    // the study keeps Eq. 6's f3 > 0 too: sech is even, f3 < 0 is f3's mirror); zero slope below.
    double th[6];
    const int n = friction_count(model);
    for (int k = 0; k < n; ++k) th[k] = is_scale_parameter(model, k) ? std::max(theta[k], 1e-3) : theta[k];
    double t = 0;
    if (model == FrictionModel::eq4) t = NonlinearFriction<NonlinearFrictionModel::eq4>::torque(th, qd, grad);
    if (model == FrictionModel::eq5) t = NonlinearFriction<NonlinearFrictionModel::eq5>::torque(th, qd, grad);
    if (model == FrictionModel::eq6) t = NonlinearFriction<NonlinearFrictionModel::eq6>::torque(th, qd, grad);
    for (int k = 0; grad && k < n; ++k) {
      if (is_scale_parameter(model, k) && !(theta[k] > 1e-3)) grad[k] = 0.0;
    }
    return t;
  }
  switch (model) {
    default: {
      const int n = friction_count(model);
      double t = 0;
      for (int k = 0; k < n; ++k) {
        const double c = linear_column(model, k, qd, tau_load);
        t += theta[k] * c;
        if (grad) grad[k] = c;
      }
      return t;
    }
  }
}

}  // namespace dyncal::host
