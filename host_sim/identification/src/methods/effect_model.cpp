#include "dyncal_host/identification/methods/effect_model.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal/effect_terms.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/common/spline_basis.hpp"
#include "dyncal_host/identification/methods/butterworth.hpp"

namespace dyncal::host {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

Index effect_column_count(const std::vector<ModelEffect>& effects) {
  Index m = 0;
  for (const ModelEffect& e : effects) m += static_cast<Index>(effect_param_names(e).size());
  return m;
}

bool effect_column_steps(EffectKind kind, int column) {
  switch (kind) {
    case EffectKind::stribeck:
    case EffectKind::velocity_power:
    case EffectKind::load_friction:
      return true;
    case EffectKind::asymmetric_friction:
    case EffectKind::coupling:
      return column == 0;  // [qd > 0], sgn(v); qd [qd > 0], v and a are continuous
    default:
      return false;
  }
}

std::vector<bool> effect_columns_with_sign(const std::vector<ModelEffect>& effects) {
  std::vector<bool> out;
  for (const ModelEffect& e : effects) {
    const int width = static_cast<int>(effect_param_names(e).size());
    for (int c = 0; c < width; ++c) out.push_back(effect_column_steps(e.kind, c));
  }
  return out;
}

MatrixXd effect_columns_over_time(const std::vector<ModelEffect>& effects, const MatrixXd& q, const MatrixXd& qd,
                                  const MatrixXd& qdd, const MatrixXd& v_raw, const VectorXd& band) {
  const Index S = q.rows(), N = q.cols(), m = effect_column_count(effects);
  MatrixXd out = MatrixXd::Zero(S, N * m);
  const auto velocity = signed_velocity;
  double c[3];
  Index col = 0;
  for (const ModelEffect& e : effects) {
    const Index width = static_cast<Index>(effect_param_names(e).size());
    if (e.kind != EffectKind::load_friction) {
      const int i = e.joint, k = e.kind == EffectKind::coupling ? e.joint2 : e.joint;
      // A coupling's signed ratio r (lib/ effect_terms.hpp); 1 for the per-joint kinds.
      const double sign = e.kind == EffectKind::coupling ? e.sign * (e.shape > 0 ? e.shape : 1.0) : 1.0;
      for (Index s = 0; s < S; ++s) {
        double v, a;
        if (e.kind == EffectKind::coupling) {
          v = velocity(qd(s, i) + sign * qd(s, k), v_raw(s, i) + sign * v_raw(s, k),
                       std::hypot(band[i], sign * band[k]));
          a = qdd(s, i) + sign * qdd(s, k);
        } else {
          v = velocity(qd(s, i), v_raw(s, i), band[i]);
          a = qdd(s, i);
        }
        // The motor's v and a passed whole (second joint 0): effect_columns adds sign qd2.
        const int w = effect_columns(e.kind, e.shape, sign, q(s, i), v, a, 0.0, 0.0, 0.0, c);
        for (int x = 0; x < w; ++x) {
          out(s, i * m + col + x) = c[x];
          if (e.kind == EffectKind::coupling) out(s, k * m + col + x) = sign * c[x];
        }
      }
    }
    col += width;
  }
  return out;
}

VectorXd shape_variable_values(const StackedData& d, const ShapeVariable& v, const VectorXd& tau_model_joint) {
  switch (v.of) {
    case ShapeVariable::Of::time:
      return d.t.array() - (d.t.size() > 0 ? d.t[0] : 0.0);
    case ShapeVariable::Of::q:
      return d.q.col(v.joint);
    case ShapeVariable::Of::qd:
      return d.qd.col(v.joint);
    case ShapeVariable::Of::qdd:
      return d.qdd.col(v.joint);
    case ShapeVariable::Of::tau_model:
      return tau_model_joint;
  }
  return VectorXd();
}

MatrixXd shape_series(const StackedData& d, int joint, const ShapeVariable& v, const VectorXd& x,
                      const std::vector<double>& knots) {
  MatrixXd series = shape_basis(x, knots, shape_without_linear(v));
  if (!v.times_sign) return series;
  if (d.qd_raw.rows() != series.rows()) throw InputError("internal: a shape times the friction sign needs qd_raw");
  for (Index s = 0; s < series.rows(); ++s)
    series.row(s) *= friction_sign(d.qd_raw(s, joint), d.standstill_band[joint]);
  if (d.filter_order > 0 && d.cutoff_hz < 0.5 * d.rate_hz) {
    const ButterworthLowPass filter(d.filter_order, d.cutoff_hz, d.rate_hz);
    for (const auto& [a, b] : time_segments(d)) filter.filtfilt(series.middleRows(a, b - a));  // columns side by side
  }
  return series;
}

MatrixXd effect_design(const StackedData& d, const std::vector<ModelEffect>& effects, const VectorXd& tau_rb,
                       const VectorXd& tau_model) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  if (d.E.cols() != effect_column_count(effects) || d.E.rows() != S * N)
    throw InputError("internal: the data were not prepared with these effect terms");
  MatrixXd E = d.E;
  Index col = 0;
  for (const ModelEffect& e : effects) {
    if (e.kind == EffectKind::shape && (!shape_of_tau_model(e) || tau_model.size() == S * N)) {
      const ShapeVariable v = parse_shape_variable(e.variable, e.joint, N);
      VectorXd own;
      if (shape_of_tau_model(e))
        own =
            Eigen::Map<const VectorXd, 0, Eigen::InnerStride<>>(tau_model.data() + e.joint, S, Eigen::InnerStride<>(N));
      const MatrixXd series = shape_series(d, e.joint, v, shape_variable_values(d, v, own), e.knots);
      for (Index b = 0; b < series.cols(); ++b)
        for (Index s = 0; s < S; ++s) E(s * N + e.joint, col + b) = series(s, b);
    }
    if (e.kind == EffectKind::load_friction) {
      const int i = e.joint;
      for (Index s = 0; s < S; ++s) {
        const double v = d.qd(s, i);
        E(s * N + i, col) = std::abs(tau_rb[s * N + i]) * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0));
      }
    }
    col += static_cast<Index>(effect_param_names(e).size());
  }
  return E;
}

void set_effect_columns(StackedData& d, Index declared, const std::vector<ModelEffect>& effects,
                        const std::vector<bool>& use, const VectorXd& tau_rb, const VectorXd& tau_model) {
  const MatrixXd E = effect_design(d, effects, tau_rb, tau_model);
  const int N = static_cast<int>(d.q.cols());
  Index used = 0;
  for (const bool u : use) used += u ? 1 : 0;
  d.W.conservativeResize(Eigen::NoChange, declared + used);
  d.names.resize(static_cast<size_t>(declared));
  Index col = 0, out = declared;
  for (const ModelEffect& e : effects) {
    for (const std::string& name : effect_param_names(e)) {
      if (use[static_cast<size_t>(col)]) {
        d.W.col(out++) = E.col(col);
        d.names.push_back(name);
      }
      ++col;
    }
  }
  d.W_load.resize(0, 0);
  d.regressor_rows = [N](const StackedData& data, Index s, bool load, MatrixXd& K) {
    if (load) throw InputError("internal: a model with effect terms has no load regressor");
    K = data.W.middleRows(s * N, N);
  };
}

TermSetModel with_effect_parameters(const TermSetModel& model, const std::vector<ModelEffect>& effects,
                                    const std::vector<bool>& use) {
  TermSetModel out = model;
  size_t col = 0;
  for (const ModelEffect& e : effects) {
    for (const std::string& name : effect_param_names(e)) {
      if (use[col++]) {
        out.names.push_back(name);
        out.info.push_back(dyncal::ParamInfo{dyncal::ParamKind::term, -1, 0u, e.joint + 1});
        ++out.num_params;
      }
    }
  }
  out.regressor = nullptr;  // the effects' columns are not the compiled regressor's: rows come from StackedData::W
  return out;
}

std::vector<ShapePenalty> shape_penalties(const std::vector<ModelEffect>& effects, const std::vector<bool>& use,
                                          Index declared) {
  std::vector<ShapePenalty> out;
  Index column = declared;
  size_t col = 0;
  for (const ModelEffect& e : effects) {
    const size_t m = effect_param_names(e).size();
    const bool used = m > 0 && use[col];
    if (used && e.kind == EffectKind::shape && e.penalty > 0)
      out.push_back({e.joint, column, e.penalty, shape_roughness_rows(e.knots, shape_without_linear(e.variable))});
    for (size_t k = 0; k < m; ++k)
      if (use[col++]) ++column;
  }
  return out;
}

VectorXd effect_parameter_scales(const StackedData& d, Index declared, const TermSetModel& model,
                                 const RobotDescription& robot) {
  const Index N = d.q.cols(), S = d.t.size();
  VectorXd out(model.num_params - declared);
  for (Index i = declared; i < model.num_params; ++i) {
    const int j = model.info[static_cast<size_t>(i)].joint - 1;
    double largest = 0;
    for (Index s = 0; s < S; ++s) largest = std::max(largest, std::abs(d.W(s * N + j, i)));
    const double tau = robot.tau_max[j];
    out[i - declared] = largest > 0 ? tau / largest : tau;
  }
  return out;
}

std::vector<bool> effect_columns_without_model_torque(const std::vector<ModelEffect>& effects) {
  std::vector<bool> out;
  for (const ModelEffect& e : effects)
    for (size_t c = 0; c < effect_param_names(e).size(); ++c)
      out.push_back(e.kind != EffectKind::load_friction && !shape_of_tau_model(e));
  return out;
}

VectorXd rigid_body_torque(const StackedData& d, const VectorXd& phi) {
  return d.W.leftCols(d.num_base) * phi.head(d.num_base);
}

MatrixXd model_design(const StackedData& d, const std::vector<ModelEffect>& effects, const VectorXd& phi,
                      const VectorXd& reference) {
  const VectorXd tau_rb = rigid_body_torque(d, phi);
  VectorXd tau_model;
  if (std::any_of(effects.begin(), effects.end(), shape_of_tau_model)) {
    if (reference.size() != phi.size())
      throw InputError("a shape of tau_model needs its reference parameters (tau_model_reference)");
    // The reference model's torque: its entries at the shapes of tau_model are 0, so their columns
    // (0 here: no tau_model yet) do not enter.
    const Index P = d.W.cols();
    tau_model = d.W * reference.head(P) +
                effect_design(d, effects, rigid_body_torque(d, reference)) * reference.tail(reference.size() - P);
  }
  const MatrixXd E = effect_design(d, effects, tau_rb, tau_model);
  MatrixXd X(d.W.rows(), d.W.cols() + E.cols());
  X << d.W, E;
  return X;
}

}  // namespace dyncal::host
