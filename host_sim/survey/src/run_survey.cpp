// run_survey: the study's runs, one function per table.
#include "dyncal_host/survey/run_survey.hpp"

#include <cmath>
#include <functional>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/parallel_tasks.hpp"
#include "dyncal_host/survey/indices.hpp"
#include "dyncal_host/survey/methods/idim_iv.hpp"
#include "dyncal_host/survey/methods/methods.hpp"
#include "dyncal_host/survey/methods/optimisers.hpp"
#include "dyncal_host/survey/methods/physically_consistent.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"
#include "dyncal_host/survey/survey_data.hpp"
#include "dyncal_host/survey/survey_plots.hpp"
#include "dyncal_host/survey/tracking.hpp"

namespace dyncal::host::survey {
namespace {

using nlohmann::json;

json indices_json(const Indices& x, double seconds) {
  return json{{"e_d", x.e_d},         {"e_d_prior", x.e_d_prior}, {"e_f", x.e_f}, {"e_T", x.e_T},
              {"e_T_std", x.e_T_std}, {"e_T_abs", x.e_T_abs},     {"J_e", x.J_e}, {"J_e_prior", x.J_e_prior},
              {"e_b", x.e_b},         {"seconds", seconds}};
}

/// RMS of tau - tau_hat of every joint [Nm] (6).
json residual_rms(const Eigen::MatrixXd& tau, const Eigen::MatrixXd& tau_hat) {
  json r = json::array();
  for (Eigen::Index j = 0; j < tau.cols(); ++j)
    r.push_back(std::sqrt((tau.col(j) - tau_hat.col(j)).squaredNorm() / static_cast<double>(tau.rows())));
  return r;
}

/// Joint 3's row of Tables 5 / 6: link 3's m, X Y Z, I11..I33 from `standard`, joint 3's friction,
/// and the mean and standard deviation of its torque error [Nm].
json joint3_json(const Eigen::VectorXd& standard, const Estimate& e, const Eigen::MatrixXd& tau) {
  const auto phys = physical_parameters(standard.data() + 20);
  json row = json::array();
  for (double v : phys) row.push_back(v);
  const size_t k = friction_parameter_names(e.model).size();
  for (size_t i = 0; i < k; ++i) row.push_back(e.friction[2 * k + i]);
  const Eigen::VectorXd err = tau.col(2) - e.tau_hat.col(2);
  const double mean = err.mean();
  row.push_back(mean);
  row.push_back(std::sqrt((err.array() - mean).square().sum() / static_cast<double>(err.size() - 1)));
  return row;
}

/// Forgetting factor of the tracking study: a memory of 1 / (1 - mu) = 50 samples (0.5 s at 100 Hz),
/// short against the change (half the run); the identification runs keep MethodSettings::mu.
constexpr double kTrackingMu = 0.98;
/// Table 10's position noise: 1e-4 rad, the resolution of a 16-bit absolute encoder at the joint
/// (the survey does not state its level).
constexpr double kPositionNoise = 1e-4;

/// The tracking run: 4 periods (4 000 samples, 40 s), quick or not; the change spans the second half.
constexpr int kTrackingPeriods = 4;

/// The measured run of the Table 12 stand-in: the drive's run with the states recomputed from the
/// measured positions through IDIM-IV's measurement path (20 Hz Butterworth, central differences),
/// and the load torque from those states.
SurveyData experiment_stand_in(const RobotDescription& robot, const SurveyDataOptions& options) {
  SurveyData d = simulate_survey_data(robot, options);
  Eigen::MatrixXd q, qd, qdd;
  measured_states(d, IdimIvOptions{}, q, qd, qdd);
  d.q = q;
  d.qd = qd;
  d.qdd = qdd;
  d.tau_load = load_torque(d.q, d.qd, d.qdd, d.tau);
  return d;
}

struct Method {
  const char* name;
  bool online;
  std::function<Estimate(const SurveyData&, const MethodSettings&, FrictionModel)> run;
};

using M = FrictionModel;

/// The methods of the study, per family. The optimisers capture their settings by value.
struct Methods {
  std::vector<Method> linear, nonlinear, optimisers;
};

Methods study_methods(const OptimiserSettings& oo) {
  Methods m;
  m.linear = {
      {"pseudo-inverse", false,
       [](const SurveyData& d, const MethodSettings& s, M f) { return pseudo_inverse(d, s, f); }},
      {"Kalman", true, [](const SurveyData& d, const MethodSettings& s, M f) { return kalman_filter(d, s, f); }},
      {"exponential forgetting", true,
       [](const SurveyData& d, const MethodSettings& s, M f) { return exponential_forgetting(d, s, f); }},
  };
  m.nonlinear = {
      {"extended Kalman", true,
       [](const SurveyData& d, const MethodSettings& s, M f) { return extended_kalman_filter(d, s, 1.0, f); }},
      {"exponential forgetting", true,
       [](const SurveyData& d, const MethodSettings& s, M f) { return extended_kalman_filter(d, s, s.mu, f); }},
  };
  m.optimisers = {
      {"physically consistent LS", false,
       [](const SurveyData& d, const MethodSettings& s, M f) { return physically_consistent_ls(d, f, s); }},
      {"gradient descent", false,
       [oo](const SurveyData& d, const MethodSettings& s, M f) { return gradient_descent(d, f, s, oo); }},
      {"genetic algorithm", false,
       [oo](const SurveyData& d, const MethodSettings& s, M f) { return genetic_algorithm(d, f, s, oo); }},
      {"particle filter", false,
       [oo](const SurveyData& d, const MethodSettings& s, M f) { return particle_filter(d, f, s, oo); }},
  };
  return m;
}

/// What every run shares: the options, the method and optimiser settings, the robot's tau_max.
struct Study {
  const RobotDescription& robot;
  const SurveyOptions& options;
  MethodSettings ms;
  OptimiserSettings oo;
  std::array<double, 6> tau_max{};
  std::array<ExciteResult, 2> designs{};  ///< the excitations of the linear and the nonlinear runs
};

/// A run of the simulated drive: `periods` excitation periods, Table 7 torque noise when `noisy`.
SurveyDataOptions run_options(const Study& st, FrictionModel model, bool noisy, int periods) {
  SurveyDataOptions o;
  o.friction = model;
  o.torque_noise = noisy;
  o.periods = periods;
  o.seed = st.options.seed;
  o.design = &st.designs[is_linear(model) ? 0 : 1];
  return o;
}

json settings_json(const Study& st) {
  const SurveyOptions& o = st.options;
  return {{"seed", o.seed},
          {"quick", o.quick},
          {"prior_error", o.prior_error},
          {"prior_on", o.prior_on == PriorErrors::table5 ? "table5" : "standard"},
          {"sample_rate_hz", 100},
          {"periods", o.quick ? 1 : 2},
          {"mu", st.ms.mu},
          {"tau_max", st.tau_max},
          {"population", st.oo.population},
          {"generations", st.oo.generations}};
}

/// Which scale parameters the run determines: the joint friction scan's 95 % intervals at the
/// estimate's rigid body; open on both sides = not determined.
json undetermined_scale_parameters(const SurveyData& d, FrictionModel model, const Estimate& e) {
  std::vector<std::vector<ScaleInterval>> iv;
  friction_start(d, model, e.standard, &iv);
  json u = json::array();
  for (size_t j = 0; j < iv.size(); ++j) {
    for (const ScaleInterval& x : iv[j]) {
      if (x.open_below && x.open_above) {
        u.push_back("joint " + std::to_string(j + 1) + " " +
                    friction_parameter_names(model)[static_cast<size_t>(x.parameter)]);
      }
    }
  }
  return u;
}

/// One method's entries for one run of a model: its indices (under `noise`), which scale parameters
/// the run leaves open (physically consistent LS on a nonlinear model), and, without noise, joint
/// 3's row of Tables 5 / 6.
json method_run(const Study& st, const Method& m, const SurveyData& d, FrictionModel model, bool noisy) {
  const Estimate e = m.run(d, st.ms, model);
  const char* noise = noisy ? "with_noise" : "without_noise";
  json mj;
  mj["online"] = m.online;
  mj[noise] = indices_json(evaluate(e, d.scenario, d.tau, st.tau_max), e.seconds);
  mj[noise]["residual_rms"] = residual_rms(d.tau, e.tau_hat);
  const bool is_pcls = m.name == std::string("physically consistent LS");
  if (is_pcls && !is_linear(model)) mj["undetermined"] = undetermined_scale_parameters(d, model, e);
  if (!noisy) {
    mj["joint3"] = joint3_json(e.standard, e, d.tau);
    // The same with the CAD prior in the directions no torque determines (e_d prior's parameters).
    mj["joint3_prior"] = joint3_json(e.standard_prior, e, d.tau);
    if (is_pcls) mj["pseudo_inertia_min_eigenvalue"] = e.pseudo_inertia_min_eigenvalue;
  }
  return mj;
}

/// Relative cost of a method's run, to start the long ones first (run_parallel): the genetic
/// algorithm and the particle filter on a nonlinear model take most of the study.
double method_cost(const Method& m, FrictionModel model) {
  const bool sampler = m.name == std::string("genetic algorithm") || m.name == std::string("particle filter");
  return sampler ? (is_linear(model) ? 5.0 : 100.0) : 1.0;
}

/// Tables 5, 6, 8, 9 for one friction model: every method of its family and the optimisers, on a
/// run without and one with Table 7 noise. The runs' data are simulated first (one task each), then
/// every (run, method) pair is a task; the JSON is assembled afterwards, as a sequential run's.
struct ModelStudy {
  FrictionModel model = FrictionModel::eq7;
  std::array<SurveyData, 2> data;  // without, with noise
  std::vector<const Method*> methods;
  std::array<std::vector<json>, 2> results;  // per run, per method

  ModelStudy(const Methods& all, FrictionModel f) : model(f) {
    for (const Method& m : is_linear(f) ? all.linear : all.nonlinear) methods.push_back(&m);
    for (const Method& m : all.optimisers) methods.push_back(&m);
    for (auto& r : results) r.resize(methods.size());
  }

  void add_simulations(const Study& st, std::vector<ParallelTask>& tasks) {
    for (int noisy = 0; noisy < 2; ++noisy) {
      tasks.push_back({1, [this, &st, noisy] {
                         data[static_cast<size_t>(noisy)] = simulate_survey_data(
                             st.robot, run_options(st, model, noisy != 0, st.options.quick ? 1 : 2));
                       }});
    }
  }

  void add_methods(const Study& st, std::vector<ParallelTask>& tasks) {
    for (size_t noisy = 0; noisy < 2; ++noisy) {
      for (size_t i = 0; i < methods.size(); ++i) {
        tasks.push_back({method_cost(*methods[i], model), [this, &st, noisy, i] {
                           results[noisy][i] = method_run(st, *methods[i], data[noisy], model, noisy != 0);
                         }});
      }
    }
  }

  json assemble() const {
    json c;
    for (int noisy = 0; noisy < 2; ++noisy) {
      const char* noise = noisy ? "with_noise" : "without_noise";
      const SurveyData& d = data[static_cast<size_t>(noisy)];
      c["samples"] = d.t.size();
      c["trajectory_cond"] = d.trajectory_cond;
      c["parameters"] = friction_parameter_names(model);
      c["set_joint3"] = json::array();
      const std::vector<double> set = set_friction(d.scenario, model);
      for (int k = 0; k < friction_count(model); ++k)
        c["set_joint3"].push_back(set[static_cast<size_t>(2 * friction_count(model) + k)]);
      for (size_t i = 0; i < methods.size(); ++i) {
        json r = results[static_cast<size_t>(noisy)][i];
        if (r.contains("undetermined")) {
          c["undetermined_scale_parameters"][noise] = r["undetermined"];
          r.erase("undetermined");
        }
        c["methods"][methods[i]->name].update(r);
      }
    }
    for (auto& [name, mj] : c["methods"].items()) {
      const double j1 = mj["without_noise"]["J_e"], j2 = mj["with_noise"]["J_e"];
      mj["delta_J_e"] = (j2 - j1) / j1;
      const double p1 = mj["without_noise"]["J_e_prior"], p2 = mj["with_noise"]["J_e_prior"];
      mj["delta_J_e_prior"] = (p2 - p1) / p1;
    }
    return c;
  }
};

/// Table 10: pseudo-inverse and IDIM-IV on measured (noisy) positions, with and without the filter;
/// and without the filter but with parallel decimation of the torque and the regressor (survey
/// Sec. 3.1; factor kDecimation), which the survey's Table 10 does not separate from the filter.
constexpr int kDecimation = 5;

struct Table10Study {
  SurveyData data;
  std::array<json, 6> results;  // method-major: filter, no filter, no filter with parallel decimation
  static constexpr std::array<const char*, 2> kMethods{"pseudo-inverse", "IDIM-IV"};
  static constexpr std::array<const char*, 3> kVariants{"with_filter", "without_filter",
                                                        "without_filter_parallel_decimation"};

  void add_simulations(const Study& st, std::vector<ParallelTask>& tasks) {
    tasks.push_back({1, [this, &st] {
                       SurveyDataOptions qopt = run_options(st, FrictionModel::eq7, true, st.options.quick ? 1 : 2);
                       qopt.position_noise_std = kPositionNoise;
                       data = simulate_survey_data(st.robot, qopt);
                     }});
  }

  void add_methods(const Study& st, std::vector<ParallelTask>& tasks) {
    for (size_t k = 0; k < results.size(); ++k) {
      const bool iv = k / 3 == 1;
      const size_t variant = k % 3;
      tasks.push_back({iv ? 10.0 : 1.0, [this, &st, k, iv, variant] {
                         IdimIvOptions io;
                         io.filter = variant == 0;
                         io.decimation = variant == 2 ? kDecimation : 1;
                         const Estimate e = iv ? idim_iv(data, st.ms, io, closed_loop_of(st.robot, data))
                                               : pseudo_inverse_measured(data, st.ms, io);
                         json j = indices_json(evaluate(e, data.scenario, data.tau, st.tau_max), e.seconds);
                         j["iterations"] = e.iterations;
                         if (!e.note.empty()) j["note"] = e.note;
                         results[k] = j;
                       }});
    }
  }

  json assemble() const {
    json t10;
    t10["position_noise_std"] = kPositionNoise;
    t10["parallel_decimation"] = kDecimation;
    for (size_t mi = 0; mi < 2; ++mi) {
      json& m = t10["methods"][kMethods[mi]];
      for (size_t v = 0; v < kVariants.size(); ++v) m[kVariants[v]] = results[3 * mi + v];
      for (const char* key : {"J_e", "J_e_prior"}) {
        const double a = m["with_filter"][key], b = m["without_filter"][key];
        m[std::string("delta_") + key] = (b - a) / a;
      }
    }
    return t10;
  }
};

/// Mean and standard deviation of tau - tau_hat over all joints and samples [Nm].
std::pair<double, double> error_moments(const Eigen::MatrixXd& tau, const Eigen::MatrixXd& tau_hat) {
  const Eigen::MatrixXd diff = tau - tau_hat;
  const Eigen::ArrayXd err = Eigen::Map<const Eigen::ArrayXd>(diff.data(), diff.size());
  const double mean = err.mean();
  return {mean, std::sqrt((err - mean).square().sum() / static_cast<double>(err.size() - 1))};
}

/// Table 12, the survey's experiment (Sec. 6.6) on a stand-in: no real ER20 log exists here, so the
/// "measured" run is the simulated drive with Eq. 4 friction, Table 7 torque noise and Table 10's
/// position noise, its states from the measured positions (20 Hz filter, central differences) as
/// the survey's experiment had them; the particle filter (the survey's choice) and physically
/// consistent LS fit each of the six models on the first excitation period, judged on the torque
/// error alone: on that period (as the survey) and on the second, which the fit did not see (a
/// model with more parameters always fits its own data at least as well).
struct Table12Study {
  static constexpr std::array<FrictionModel, 6> kModels{M::eq7, M::eq8, M::eq9, M::eq4, M::eq5, M::eq6};
  SurveyData fit, validation;
  std::array<std::array<json, 2>, 6> results;  // per model: particle filter, consistent LS

  void add_simulations(const Study& st, std::vector<ParallelTask>& tasks) {
    tasks.push_back({1, [this, &st] {
                       SurveyDataOptions eopt = run_options(st, FrictionModel::eq4, true, 2);
                       eopt.position_noise_std = kPositionNoise;
                       const SurveyData ed = experiment_stand_in(st.robot, eopt);
                       const Eigen::Index half = ed.q.rows() / 2;
                       fit = sample_rows(ed, 0, half);
                       validation = sample_rows(ed, half, ed.q.rows() - half);
                     }});
  }

  void add_methods(const Study& st, const Methods& all, std::vector<ParallelTask>& tasks) {
    for (size_t mi = 0; mi < kModels.size(); ++mi) {
      for (size_t k = 0; k < 2; ++k) {
        const Method* m = k == 0 ? &all.optimisers[3] : &all.optimisers[0];  // particle filter, consistent LS
        tasks.push_back({method_cost(*m, kModels[mi]) / 2, [this, &st, m, mi, k] {
                           const Estimate e = m->run(fit, st.ms, kModels[mi]);
                           Estimate v = e;
                           complete_estimate(v, validation, st.ms);
                           const auto [mean, sd] = error_moments(fit.tau, e.tau_hat);
                           const auto [v_mean, v_sd] = error_moments(validation.tau, v.tau_hat);
                           results[mi][k] = {{"mean", mean},
                                             {"std", sd},
                                             {"validation_mean", v_mean},
                                             {"validation_std", v_sd},
                                             {"seconds", e.seconds}};
                         }});
      }
    }
  }

  json assemble(const Methods& all) const {
    json t12;
    t12["plant"] = "eq4";
    for (size_t mi = 0; mi < kModels.size(); ++mi) {
      t12["methods"][all.optimisers[3].name][model_key(kModels[mi])] = results[mi][0];
      t12["methods"][all.optimisers[0].name][model_key(kModels[mi])] = results[mi][1];
    }
    return t12;
  }
};

/// Fig. 4: beta of joint 3 changing over the samples of noisy Eq. 7 and Eq. 4 runs.
struct TrackingStudy {
  static constexpr std::array<FrictionModel, 2> kModels{FrictionModel::eq7, FrictionModel::eq4};
  std::array<SurveyData, 2> data;
  std::array<std::vector<TrackingResult>, 2> runs;  // per model: every profile's results in order

  void add_simulations(const Study& st, std::vector<ParallelTask>& tasks) {
    for (size_t mi = 0; mi < 2; ++mi) {
      tasks.push_back({1, [this, &st, mi] {
                         data[mi] =
                             simulate_survey_data(st.robot, run_options(st, kModels[mi], true, kTrackingPeriods));
                       }});
    }
  }

  void add_methods(const Study& st, std::vector<ParallelTask>& tasks) {
    for (size_t mi = 0; mi < 2; ++mi) {
      tasks.push_back(
          {5, [this, &st, mi] {
             const SurveyData& td = data[mi];
             // dyncal's hybrid calibrates offline on the samples before the change starts (N < S / 2).
             const Estimate calibration =
                 physically_consistent_ls(sample_rows(td, 0, td.q.rows() / 2), kModels[mi], st.ms);
             for (ChangeProfile p : {ChangeProfile::step, ChangeProfile::ramp, ChangeProfile::second_order}) {
               std::vector<TrackingResult> r = track_viscous_friction(td, st.ms, p, 3, kTrackingMu);
               r.push_back(track_friction_after_calibration(td, calibration, st.ms, p, 3, kTrackingMu));
               runs[mi].insert(runs[mi].end(), r.begin(), r.end());
             }
           }});
    }
  }

  json assemble() const {
    json tracking;
    tracking["mu"] = kTrackingMu;
    for (const auto& model_runs : runs) {
      for (const TrackingResult& t : model_runs) {
        tracking["methods"][t.method][to_string(t.profile)] = {
            {"lag", t.relative_lag}, {"scatter", t.relative_scatter}, {"mean_abs", t.relative_error}};
      }
    }
    return tracking;
  }
};

}  // namespace

json run_survey(const RobotDescription& robot, const SurveyOptions& o, SurveySeries* series) {
  Study st{robot, o, {}, {}, {}, {}};
  const int jobs = o.jobs > 0 ? o.jobs : default_jobs();
  st.oo.seed = o.seed;
  if (o.quick) {  // a sixth of the genetic algorithm's and the particle filter's evaluations
    st.oo.population = 60;
    st.oo.generations = 500;
  }
  st.ms.prior = cad_prior(o.prior_error, o.seed, o.prior_on);
  for (int j = 0; j < 6; ++j) st.tau_max[j] = robot.tau_max[j];
  const Methods methods = study_methods(st.oo);
  std::vector<ModelStudy> models;
  for (M model : {M::eq7, M::eq8, M::eq9, M::eq4, M::eq5, M::eq6}) models.emplace_back(methods, model);
  Table10Study t10;
  Table12Study t12;
  TrackingStudy tracking;
  // Three rounds: the two excitation designs (every run plays one of them), every run's data, then
  // every method on them.
  std::vector<ParallelTask> designs, simulations, fits;
  for (size_t k = 0; k < st.designs.size(); ++k) {
    designs.push_back(
        {1, [&st, k] { st.designs[k] = study_excitation(st.robot, k == 0 ? M::eq7 : M::eq4, st.options.seed); }});
  }
  run_parallel(std::move(designs), jobs, "survey: excitation designs");
  for (ModelStudy& m : models) m.add_simulations(st, simulations);
  t10.add_simulations(st, simulations);
  t12.add_simulations(st, simulations);
  tracking.add_simulations(st, simulations);
  run_parallel(std::move(simulations), jobs, "survey: simulated drive runs");
  for (ModelStudy& m : models) m.add_methods(st, fits);
  t10.add_methods(st, fits);
  t12.add_methods(st, methods, fits);
  tracking.add_methods(st, fits);
  run_parallel(std::move(fits), jobs, "survey: identification methods");
  json result;
  result["settings"] = settings_json(st);
  for (const ModelStudy& m : models) result["models"][model_key(m.model)] = m.assemble();
  result["table10"] = t10.assemble();
  result["table12"] = t12.assemble(methods);
  result["tracking"] = tracking.assemble();
  if (series) {
    for (const ModelStudy& m : models) {
      if (m.model == M::eq7 || m.model == M::eq4)
        series->trajectories.push_back({model_key(m.model), m.data[0].t, m.data[0].q});
    }
    for (size_t mi = 0; mi < tracking.kModels.size(); ++mi)
      series->tracking.push_back({model_key(tracking.kModels[mi]), tracking.runs[mi]});
  }
  return result;
}

}  // namespace dyncal::host::survey
