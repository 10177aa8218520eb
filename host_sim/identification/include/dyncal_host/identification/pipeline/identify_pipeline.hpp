#pragma once
// The identification pipeline for one compiled robot and one built term set (host side), compiled
// once: the robot enters through its TermSetModel (term_set_model.hpp), the generated regressor and
// the lib/ estimators of the model's size.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/identification/methods/butterworth.hpp"
#include "dyncal_host/identification/methods/consistent_least_squares.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/identification/methods/identifiability.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/kept_samples.hpp"
#include "dyncal_host/identification/pipeline/parameter_prior.hpp"
#include "dyncal_host/model/stacked_data.hpp"
#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

class IdentifyPipeline {
 public:
  /// `robot` and `options` are referenced, not copied: they must outlive the pipeline; `model` is
  /// the compiled robot's TermSetModel of options.terms (or it with effect parameters appended,
  /// with_effect_parameters: effect_scales then gives their scales(), the last entries).
  IdentifyPipeline(const RobotDescription& robot, const IdentifyOptions& options, const TermSetModel& model,
                   const Eigen::VectorXd& effect_scales = Eigen::VectorXd());

  /// As below on a copy of `log`, which the caller keeps.
  StackedData prepare(const JointLog& log, bool dense, const Eigen::VectorXd* band_override = nullptr) const {
    return prepare(JointLog(log), dense, band_override);
  }

  /// Filtering, differentiation, regressor, parallel filtering and decimation (Gautier 1997), each
  /// segment of `log` (on a uniform grid, uniform_grid.hpp) on its own: nothing is filtered or
  /// differentiated across a segment boundary, and one cut-off period is dropped at both ends of
  /// every segment, where differentiation and filtering are one-sided.
  ///
  /// Memory: the log is consumed. Its torques are filtered first and released; its positions are
  /// filtered in place and, with its time stamps, shrunk to the kept samples in their own buffers
  /// (kept_samples.hpp). The rest is processed one joint at a time, and only what the regressor is
  /// computed from is kept at the decimated samples; dense: also fill W (and W_load) for the
  /// consumers that need the matrix (StackedData).
  /// band: the standstill band to use instead of the log's own (IDIM-IV's noise-free simulations
  /// take the measured log's, so that their friction-sign columns are built as the measured ones).
  StackedData prepare(JointLog&& log, bool dense, const Eigen::VectorXd* band_override = nullptr) const;

  /// True when robot.json's coupled motors are modelled (its transmission, not --friction-per-joint):
  /// a parameter file's "friction_per": "motor". Coupled motors of the model (IdentifyOptions::motors)
  /// are in its model string.
  bool models_coupled_motors() const { return robot_coupled_; }

  /// What the final fit reports besides phi and stdev.
  struct FitDetails {
    double cond = 0;                ///< cond(W) of the full stacked (weighted) regressor
    ConsistentSolution consistent;  ///< pcls, gd, ga, pf
    std::vector<int> held;          ///< sign constraints: indices held at 0
    double inflation = 1;           ///< the residual's autocorrelation factor S / n_eff
    DeterminedFit decision;         ///< the parameters the log does not determine (identifiability.hpp)
    Eigen::VectorXd data_stdev;     ///< pcls, gd, ga, pf, and ols/wls with a prior: the std of the data alone
    /// ols/wls with a prior, and gd/ga/pf when the log leaves parameters undetermined (their std is
    /// then the posterior's with the inertials as prior): per parameter, the share of its
    /// information from the data (data_share
    /// of parameter_prior.hpp; NaN without a prior); empty otherwise.
    Eigen::VectorXd data_share;
    /// Input of the final fit (its folds take it from `decided`): ols/wls with a prior weigh the data
    /// rows this many times their white-noise weight against the prior (1; 1 / S / n_eff: their
    /// effective information; run_identify chooses by cross-validation).
    double data_weight = 1;
    double decision_inflation = 1;  ///< the OLS residual's autocorrelation factor the decision and pcls use
  };

  /// Fits on the samples with train[s] true. Writes phi and parameter standard deviations (P).
  /// Final fit (`details` given): decides which parameters the data alone determine
  /// (determined_least_squares, with the residual's autocorrelation factor of the OLS fit). ols and
  /// wls with a usable prior() then fit every parameter as the MAP estimate (data rows and the
  /// prior's pseudo-rows, parameter_prior.hpp; the std posterior ones, details->data_share per
  /// parameter), holding at 0 only an undetermined parameter without a prior; without a prior (and
  /// for iv's start) the undetermined ones are held at 0 (std NaN). The std are the white-noise
  /// figures times the square root of the autocorrelation factor S / n_eff of the final residual
  /// (streamed_autocorrelation_inflation, N passes over the data), written into details->inflation.
  /// A fold's fit (`decided` given: the final fit's details) treats the same parameters as
  /// undetermined, weighs pcls's data by the same autocorrelation factor and writes the white-noise
  /// figures. pcls, gd, ga, pf start from the weighted least-squares fit with the undetermined
  /// parameters at 0 and fit every parameter (the prior or the search range holds those). Throws
  /// InputError.
  void fit(const StackedData& data, const std::vector<char>& train, Eigen::VectorXd& phi, Eigen::VectorXd& stdev,
           FitDetails* details, const FitDetails* decided = nullptr) const;

  /// The prior the ols and wls fits are the MAP estimate with (parameter_prior.hpp); not usable for
  /// another method, with --prior-std 0, or for a robot without inertials.
  const ParameterPrior& prior() const { return prior_; }
  /// Physical scale of each parameter (parameter_scales.hpp).
  const Eigen::VectorXd& scales() const { return scale_; }

  const TermSetModel& model() const { return model_; }

  /// Penalised shapes among the model's effect columns (effect_model.hpp's shape_penalties): the
  /// least squares of every method that fits effect terms (wls, ols; pcls, gd, ga and pf build
  /// their problem from its triangular factor; identify refuses effects with kf and rls, and iv fits
  /// eq7) gains their rows, each scaled by sqrt(n_j lambda) with n_j the fit's rows of the shape's
  /// joint and weighed as that joint's rows.
  void set_shape_penalties(std::vector<ShapePenalty> penalties) { penalties_ = std::move(penalties); }

  /// A regressor column built from an unfiltered velocity's sign, and therefore low-passed in
  /// parallel at the log's rate (StackedData::filtered_terms): term t (Coulomb or power) of joint
  /// or motor m (0-based) in column col, on joint m's row, or, for a coupled motor, on every row j
  /// times its transmission entry.
  struct FilteredTerm {
    unsigned t;
    int m;
    int col;
    bool coupled;
  };

 private:
  /// ols, wls: the MAP estimate's inputs (the data's triangular factor without the prior's rows,
  /// empty: no MAP fit), for the final fit's statistics.
  struct MapData {
    Eigen::MatrixXd R;             // the data's triangular factor (without the prior's rows); empty: no MAP fit
    double sigma2 = 1;             // the data rows' residual variance
    std::vector<int> held;         // parameters held at 0 (no prior and undetermined, or sign constraints)
    std::vector<int> unsupported;  // of them, those without a prior the data do not determine (std NaN)
  };
  /// ols, wls, iv: least squares of the parameters the data determine, then (with a usable prior,
  /// not iv) the MAP estimate with the prior's pseudo-rows weighed by data_weight.
  void fit_least_squares_with_prior(LeastSquaresFit& ls, const std::vector<int>* dropped, double decision_inflation,
                                    double data_weight, Eigen::VectorXd& phi, Eigen::VectorXd& stdev,
                                    FitDetails* details, MapData& map_data) const;
  /// pcls, gd, ga, pf: the consistent fit (or search) started from the weighted least squares of `ls`.
  void fit_consistent(LeastSquaresFit& ls, const StackedData& data, const std::vector<char>& train,
                      const std::vector<int>* dropped, double decision_inflation, Eigen::VectorXd& phi,
                      Eigen::VectorXd& stdev, FitDetails* details, MapData& map_data,
                      ParameterPrior& search_prior) const;
  /// The final fit's std: the MAP estimate's spread, pcls's covariance, or the white-noise figures,
  /// with the residual's autocorrelation (details.inflation).
  void final_statistics(const StackedData& data, const std::vector<char>& train, const Eigen::VectorXd& phi,
                        Eigen::VectorXd& stdev, FitDetails& details, const MapData& map_data,
                        const ParameterPrior& search_prior, double data_weight) const;
  void process_segment(JointLog& log, Eigen::Index a, Eigen::Index b, const ButterworthLowPass& filter,
                       const Eigen::VectorXd& band, const KeptSamples& kept, Eigen::Index k0, StackedData& out) const;
  Eigen::VectorXd standstill_band(const JointLog& log,
                                  const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments) const;
  void least_squares(const LeastSquaresFit& ls, const std::vector<int>* forced, double inflation, bool constrain,
                     Eigen::VectorXd& phi, Eigen::VectorXd& stdev, double* cond, std::vector<int>* held,
                     DeterminedFit* decision) const;
  void constrain_signs(const LeastSquaresFit& ls, const std::vector<int>& dropped, Eigen::VectorXd& phi,
                       Eigen::VectorXd& stdev, std::vector<int>* held) const;

  const RobotDescription& robot_;
  const IdentifyOptions& opt_;
  const TermSetModel& model_;
  int N, P;
  Eigen::MatrixXd motor_;                ///< motor_velocity_map(robot_, ...): v = T qd (N x N)
  bool robot_coupled_;                   ///< robot.json's coupling is in motor_
  std::vector<int> coupled_;             ///< motors turning with more than their own joint (0-based)
  std::vector<FilteredTerm> filtered_;   ///< StackedData::filtered_terms' columns
  Eigen::VectorXd scale_;                ///< parameter_scales(robot_, model_)
  ParameterPrior prior_;                 ///< ols, wls: parameter_prior(robot_, model_, --prior-std)
  std::vector<ShapePenalty> penalties_;  ///< set_shape_penalties
};

/// Runs the whole `identify` job for one robot and term set; preparing the data consumes the log.
/// Throws InputError.
IdentifyResult run_identify(const RobotDescription& robot, const TermSetModel& model, JointLog&& log,
                            const IdentifyOptions& opt);

}  // namespace dyncal::host
