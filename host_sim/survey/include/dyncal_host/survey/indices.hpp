#pragma once
// The survey's evaluation indices (Sec. 5: e_T, e_T_Std, e_d, e_f, J_e; plus e_b) of an estimate
// against the set parameters of the study's run, and the levels of Tables 1-4.

#include <Eigen/Core>
#include <array>

#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/survey/methods/estimate.hpp"

namespace dyncal::host::survey {

/// Survey Sec. 5 indices; e_d and e_f are means of |(set - est) / set| over the parameters whose
/// set value is nonzero (m, X Y Z, I11..I33 of every link, Table 5's parametrisation).
struct Indices {
  double e_d = 0;        ///< inertial parameter error, standard parameters as the method gives them
  double e_d_prior = 0;  ///< the same with the CAD prior (Estimate::standard_prior)
  double e_f = 0;        ///< friction parameter error
  double e_T = 0;        ///< |Mean((tau - tau_hat) / tau_max)| (signed mean, as the published numbers)
  double e_T_std = 0;    ///< Std((tau - tau_hat) / tau_max)
  double e_T_abs = 0;    ///< Mean(|tau - tau_hat| / tau_max), Sec. 5.1 read literally
  double J_e = 0;        ///< e_d + e_f + e_T + e_T_std
  double J_e_prior = 0;  ///< e_d_prior + e_f + e_T + e_T_std
  double e_b = 0;        ///< base parameter error: mean |(set - est) / set| over nonzero set base parameters
};

/// Mean |(set[i] - est[i]) / set[i]| over the i < n with set[i] != 0 (0 if there is none).
double mean_relative_error(const double* set, const double* est, int n);

/// One link's term of e_d (`link` 0-based): the mean |(set - est) / set| of its Table 5 parameters
/// (m, X Y Z, I11..I33 about the centre of mass) with nonzero set values, from 60 standard parameters.
double link_inertial_error(const Eigen::VectorXd& phi_standard, int link);

/// e_d of survey Sec. 5 for 60 standard parameters: link_inertial_error averaged over the links.
double inertial_parameter_error(const Eigen::VectorXd& phi_standard);

/// tau: the measured torque the method was given (S x 6); tau_max per joint [Nm].
Indices evaluate(const Estimate& est, const Scenario& scenario, const Eigen::MatrixXd& tau,
                 const std::array<double, 6>& tau_max);

/// Level letter of survey Tables 1-4: 'A' below a, 'B' below b, else 'C'.
char level(double value, double a, double b);

}  // namespace dyncal::host::survey
