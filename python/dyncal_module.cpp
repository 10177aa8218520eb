// `import dyncal`: the library from Python (docs/python.md). Robots and their generated regressors
// as numpy arrays, and the CLI's commands (identify, predict, diagnose, payload) run in-process with
// the CLI's own code: a command returns the document its --report writes, as Python objects with
// every JSON array of numbers as a numpy array, plus the printed report. Errors raise
// dyncal.InputError with the CLI's one-line message.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "../host_sim/app/commands.hpp"
#include "../host_sim/app/options.hpp"
#include "../host_sim/app/report_outputs.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/interrupt.hpp"
#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/common/progress.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/parameter_set.hpp"

namespace py = pybind11;

namespace {

using dyncal::host::InputError;

/// A robot folder and its compiled model.
struct Robot {
  dyncal::host::RobotDescription description;
  const dyncal::host::CompiledRobot* model = nullptr;
  std::string robots_dir;
};

Robot load(const std::string& name, const std::string& robots_dir) {
  Robot r;
  r.robots_dir = robots_dir.empty() ? dyncal::host::default_robots_dir() : robots_dir;
  r.description = dyncal::host::load_checked_robot(r.robots_dir, name);  // the CLI's one check
  r.model = &dyncal::host::compiled_robot_for(r.description);
  return r;
}

std::vector<std::string> base_parameter_names(const Robot& r) {
  for (const auto& m : r.model->models)
    if (m.num_base > 0) return {m.names.begin(), m.names.begin() + m.num_base};
  return {};
}

/// Rows of a (S x N) or (N) array as an S x N matrix; `what` names the argument in errors.
Eigen::MatrixXd rows_of(const py::array_t<double, py::array::c_style | py::array::forcecast>& a, int n,
                        const char* what, bool& single) {
  single = a.ndim() == 1;
  if (a.ndim() < 1 || a.ndim() > 2 || a.shape(a.ndim() - 1) != n)
    throw InputError(std::string(what) + ": expected shape (" + std::to_string(n) + ",) or (S, " + std::to_string(n) +
                     "), one column per joint");
  const Eigen::Index s = a.ndim() == 1 ? 1 : a.shape(0);
  Eigen::MatrixXd m(s, n);
  const double* p = a.data();
  for (Eigen::Index i = 0; i < s; ++i)
    for (int j = 0; j < n; ++j) {
      m(i, j) = p[i * n + j];
      if (!std::isfinite(m(i, j)))
        throw InputError(std::string(what) + "[" + std::to_string(i) + ", " + std::to_string(j) + "] is not finite");
    }
  return m;
}

/// Y_b(q, qd, qdd): (N, P) for one sample, (S, N, P) for S samples.
py::array_t<double> regressor(const Robot& r, const py::array_t<double, py::array::c_style | py::array::forcecast>& q,
                              const py::array_t<double, py::array::c_style | py::array::forcecast>& qd,
                              const py::array_t<double, py::array::c_style | py::array::forcecast>& qdd) {
  const int n = r.description.num_joints, p = r.model->num_base;
  bool s1 = false, s2 = false, s3 = false;
  const Eigen::MatrixXd Q = rows_of(q, n, "q", s1), QD = rows_of(qd, n, "qd", s2), QDD = rows_of(qdd, n, "qdd", s3);
  if (Q.rows() != QD.rows() || Q.rows() != QDD.rows() || s1 != s2 || s1 != s3)
    throw InputError("q, qd, qdd: the same shape is needed");
  const Eigen::Index s = Q.rows();
  py::array_t<double> out(s1 ? std::vector<py::ssize_t>{n, p} : std::vector<py::ssize_t>{s, n, p});
  double* o = out.mutable_data();
  for (Eigen::Index i = 0; i < s; ++i) {
    const Eigen::MatrixXd Y =
        r.model->base_regressor(Q.row(i).transpose(), QD.row(i).transpose(), QDD.row(i).transpose());
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < p; ++k) o[(i * n + j) * p + k] = Y(j, k);
  }
  return out;
}

/// A JSON value as Python: objects as dicts, arrays of numbers (of any depth, rectangular) as numpy.
py::object to_python(const nlohmann::json& j);

bool numeric_array(const nlohmann::json& j, std::vector<py::ssize_t>& shape, std::size_t depth = 0) {
  if (!j.is_array() || j.empty()) return false;
  if (depth == shape.size()) shape.push_back(static_cast<py::ssize_t>(j.size()));
  if (shape[depth] != static_cast<py::ssize_t>(j.size())) return false;
  for (const auto& x : j) {
    if (x.is_number()) {
      if (depth + 1 != shape.size()) return false;
    } else if (!numeric_array(x, shape, depth + 1)) {
      return false;
    }
  }
  return true;
}

void flatten(const nlohmann::json& j, std::vector<double>& out) {
  if (j.is_number()) {
    out.push_back(j.get<double>());
    return;
  }
  for (const auto& x : j) flatten(x, out);
}

py::object to_python(const nlohmann::json& j) {
  std::vector<py::ssize_t> shape;
  if (numeric_array(j, shape)) {
    std::vector<double> flat;
    flatten(j, flat);
    py::array_t<double> a(shape);
    std::copy(flat.begin(), flat.end(), a.mutable_data());
    return std::move(a);
  }
  if (j.is_object()) {
    py::dict d;
    for (const auto& [k, v] : j.items()) d[py::str(k)] = to_python(v);
    return std::move(d);
  }
  if (j.is_array()) {
    py::list l;
    for (const auto& x : j) l.append(to_python(x));
    return std::move(l);
  }
  if (j.is_boolean()) return py::bool_(j.get<bool>());
  if (j.is_number_integer()) return py::int_(j.get<long long>());
  if (j.is_number()) return py::float_(j.get<double>());
  if (j.is_string()) return py::str(j.get<std::string>());
  return py::none();
}

/// keyword arguments as command-line options: a_b=v is --a-b v; True a flag, False left out; a
/// list repeats the option (--data A --data B).
std::vector<std::string> options_of(const py::kwargs& kwargs) {
  std::vector<std::string> args;
  for (const auto& [key, value] : kwargs) {
    std::string name = "--" + py::str(key).cast<std::string>();
    for (auto& c : name)
      if (c == '_') c = '-';
    if (name == "--report") throw InputError("report: the command's report is what it returns");
    const auto add = [&](const py::handle& v) {
      if (py::isinstance<py::bool_>(v)) {
        if (v.cast<bool>()) args.push_back(name);
        return;
      }
      args.push_back(name);
      args.push_back(py::str(v).cast<std::string>());
    };
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
      for (const auto& v : value) add(v);
    } else {
      add(value);
    }
  }
  return args;
}

/// Runs `dyncal COMMAND OPTIONS --report TMP` in-process: the report document and the printed text.
py::dict run_command(const std::string& command, const py::kwargs& kwargs) {
  const auto report = std::filesystem::temp_directory_path() /
                      ("dyncal_python_" + std::to_string(::getpid()) + "_" + command + ".json");
  std::vector<std::string> args{"dyncal", command};
  for (auto& a : options_of(kwargs)) args.push_back(std::move(a));
  {  // the report's command_line: the equivalent dyncal command (without the module's own --report)
    std::vector<char*> line;
    for (auto& a : args) line.push_back(a.data());
    dyncal::app::set_command_line(static_cast<int>(line.size()), line.data());
  }
  args.push_back("--report");
  args.push_back(report.string());
  CLI::App app{"dyncal"};
  app.require_subcommand(1);
  dyncal::app::Action run;
  dyncal::app::add_commands(app, run);
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), const_cast<char**>(argv.data()));
  } catch (const CLI::CallForHelp&) {  // help=True: the command's help text, as `dyncal COMMAND --help` prints it
    py::dict out;
    out["help"] = app.get_subcommand(command)->help();
    return out;
  } catch (const CLI::ParseError& e) {
    throw InputError(e.what());
  }
  std::ostringstream text;
  std::streambuf* saved = std::cout.rdbuf(text.rdbuf());
  int code = 0;
  try {
    code = run ? run() : 0;
  } catch (...) {
    std::cout.rdbuf(saved);
    std::filesystem::remove(report);
    throw;
  }
  std::cout.rdbuf(saved);
  // Exit 1 with a report: a gate (gate=, require=) failed; the report says which items (docs/gates.md).
  if (code != 0 && !(code == 1 && std::filesystem::exists(report)))
    throw InputError("dyncal " + command + " exited with " + std::to_string(code));
  std::ifstream in(report);
  nlohmann::json doc = nlohmann::json::parse(in);
  std::filesystem::remove(report);
  if (code != 0 && !(doc.contains("gate") && !doc["gate"].value("passed", true)))
    throw InputError("dyncal " + command + " exited with " + std::to_string(code));
  py::dict out = to_python(doc).cast<py::dict>();
  out["report_text"] = text.str();
  return out;
}

/// A log read as the CLI reads --data (LogOption: formats, columns, currents, several files, the
/// plausibility check against the robot's limits).
dyncal::host::JointLog read_log(const Robot& r, const std::vector<std::string>& paths, const std::string& format,
                                const std::string& columns, const std::string& torque_from, bool merge_on_time,
                                bool drop_outliers, const std::string& topic, const std::string& effort,
                                const std::string& clock) {
  dyncal::app::LogOption o;
  o.robot.name = r.description.name;
  o.robot.robots_dir = r.robots_dir;
  o.format = format;
  o.columns = columns;
  o.torque_from = torque_from;
  o.data = paths;
  o.merge_on_time = merge_on_time;
  o.drop_outliers = drop_outliers;
  o.topic = topic;
  o.effort = effort;
  o.clock = clock;
  if (paths.empty()) throw InputError("read_log: no log path given");
  return o.load_log(r.description);
}

/// A log from arrays: t (S) [s], q and tau (S, N) [rad, Nm], qd (S, N) optional.
dyncal::host::JointLog log_of(const Robot& r, const Eigen::VectorXd& t, const Eigen::MatrixXd& q,
                              const Eigen::MatrixXd& tau, const std::optional<Eigen::MatrixXd>& qd) {
  const int n = r.description.num_joints;
  if (q.rows() != t.size() || tau.rows() != t.size() || q.cols() != n || tau.cols() != n ||
      (qd && (qd->rows() != t.size() || qd->cols() != n)))
    throw InputError("Log: t (S), q, tau" + std::string(qd ? ", qd" : "") + " (S, " + std::to_string(n) +
                     "), one row per sample");
  if (!t.allFinite() || !q.allFinite() || !tau.allFinite() || (qd && !qd->allFinite()))
    throw InputError("Log: a value is NaN or infinite");
  dyncal::host::JointLog log;
  log.t = t;
  log.q = q;
  log.tau = tau;
  log.has_qd = qd.has_value();
  log.qd = qd ? *qd : Eigen::MatrixXd::Zero(q.rows(), n);
  log.qdd = Eigen::MatrixXd::Zero(q.rows(), n);
  log.source = "arrays";
  return log;
}

/// identify()'s options from the CLI's option names (defaults the CLI's): the model string parsed as
/// --model parses it.
dyncal::host::IdentifyOptions identify_options(const Robot& r, const std::string& method, const std::string& model,
                                               double cutoff_hz, int filter_order, int decimate, int folds,
                                               double block_seconds, double validate_last, double prior_std,
                                               double min_speed, bool sign_constraints, bool friction_per_joint,
                                               bool strict, std::uint64_t seed) {
  dyncal::host::IdentifyOptions o;
  const dyncal::host::ModelSpec spec = dyncal::host::parse_model_spec(model, r.description.num_joints);
  o.method = method;
  o.terms = spec.terms;
  o.effects = spec.effects;
  o.motors = spec.motors;
  o.cutoff_hz = cutoff_hz;
  o.filter_order = filter_order;
  o.decimate = decimate;
  o.folds = folds;
  o.block_seconds = block_seconds;
  o.validate_last = validate_last;
  o.prior_std = prior_std;
  o.min_speed_fraction = min_speed;
  o.sign_constraints = sign_constraints;
  o.friction_per_joint = friction_per_joint;
  o.strict = strict;
  o.seed = seed;
  return o;
}

/// Per-joint metrics as numpy arrays keyed by name (index j: joint j + 1).
py::dict metrics_of(const std::vector<dyncal::host::JointMetrics>& joints) {
  const auto column = [&](double dyncal::host::JointMetrics::*field) {
    Eigen::VectorXd v(static_cast<Eigen::Index>(joints.size()));
    for (size_t j = 0; j < joints.size(); ++j) v[static_cast<Eigen::Index>(j)] = joints[j].*field;
    return v;
  };
  py::dict d;
  d["rms"] = column(&dyncal::host::JointMetrics::rms);
  d["rms_tau"] = column(&dyncal::host::JointMetrics::rms_tau);
  d["relative_rms"] = column(&dyncal::host::JointMetrics::relative_rms);
  d["r2"] = column(&dyncal::host::JointMetrics::r2);
  d["e_T_abs"] = column(&dyncal::host::JointMetrics::e_T_abs);
  d["e_T_abs_std"] = column(&dyncal::host::JointMetrics::e_T_abs_std);
  return d;
}

}  // namespace

namespace {

/// dyncal.Robot: a robot folder, its generated regressor and dynamics as numpy.
void bind_robot(py::module_& m) {
  py::class_<Robot>(m, "Robot",
                    "A robot folder (robots/<name>/robot.json) and its compiled model. Robot(name, robots_dir='') "
                    "raises InputError for an unknown or malformed robot, or one this build did not compile.")
      .def(py::init(&load), py::arg("name"), py::arg("robots_dir") = "")
      .def_property_readonly("name", [](const Robot& r) { return r.description.name; })
      .def_property_readonly("joints", [](const Robot& r) { return r.description.num_joints; })
      .def_property_readonly("joint_names", [](const Robot& r) { return r.description.joint_names; })
      .def_property_readonly("base_parameter_names", &base_parameter_names,
                             "names of the base parameters (Gautier), the columns of regressor()")
      .def_property_readonly("q_min", [](const Robot& r) { return r.description.q_min; })
      .def_property_readonly("q_max", [](const Robot& r) { return r.description.q_max; })
      .def_property_readonly("qd_max", [](const Robot& r) { return r.description.qd_max; })
      .def_property_readonly("tau_max", [](const Robot& r) { return r.description.tau_max; })
      .def("regressor", &regressor, py::arg("q"), py::arg("qd"), py::arg("qdd"),
           "The generated base regressor Y_b(q, qd, qdd) [rad, rad/s, rad/s^2]: tau = Y_b phi_b [Nm]. Arrays of "
           "shape (N,) give (N, P); (S, N) give (S, N, P), P = len(base_parameter_names).")
      .def_property_readonly(
          "nominal_standard",
          [](const Robot& r) {
            return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(
                r.model->nominal_standard.data(), static_cast<Eigen::Index>(r.model->nominal_standard.size())));
          },
          "the standard parameters of robot.json's inertials (10 per link: m, m c [3], I about the joint frame [6])")
      .def(
          "standard_to_base",
          [](const Robot& r, const Eigen::VectorXd& phi) {
            if (phi.size() != r.model->num_standard)
              throw InputError("phi: " + std::to_string(phi.size()) + " values, the robot has " +
                               std::to_string(r.model->num_standard) + " standard parameters");
            return r.model->standard_to_base(phi);
          },
          py::arg("phi"), "The base parameters (Gautier) of the standard parameters phi.")
      .def(
          "inverse_dynamics",
          [](const Robot& r, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
             const Eigen::VectorXd& phi) {
            const int n = r.description.num_joints;
            if (q.size() != n || qd.size() != n || qdd.size() != n || phi.size() != r.model->num_standard)
              throw InputError("inverse_dynamics: q, qd, qdd of " + std::to_string(n) + " values and phi of " +
                               std::to_string(r.model->num_standard));
            return r.model->inverse_dynamics(q, qd, qdd, phi);
          },
          py::arg("q"), py::arg("qd"), py::arg("qdd"), py::arg("phi"),
          "tau [Nm] = ID(q, qd, qdd; phi) of one sample, the generated Newton-Euler (not the regressor).")
      .def("__repr__", [](const Robot& r) {
        return "<dyncal.Robot " + r.description.name + ", " + std::to_string(r.description.num_joints) + " joints>";
      });
}

/// set_progress and the CLI's commands run in-process (identify, predict, diagnose, payload).
void bind_commands(py::module_& m) {
  m.def(
      "set_progress",
      [](py::object callback) {
        if (callback.is_none()) {
          dyncal::host::set_progress_sink({});
          return;
        }
        dyncal::host::set_progress_sink([callback](const dyncal::host::ProgressUpdate& u) {
          py::gil_scoped_acquire gil;
          callback(u.task, u.done, u.total, u.finished);
        });
      },
      py::arg("callback"),
      "Progress of the long commands (diagnose, identify's folds): callback(task, done, total, finished) is "
      "called as they go, at most once per 1 % of a task; None (the default) keeps them quiet.");
  // The callback must not outlive the interpreter.
  py::module_::import("atexit").attr("register")(py::cpp_function([] { dyncal::host::set_progress_sink({}); }));

  for (const char* command : {"identify", "predict", "diagnose", "payload"}) {
    const std::string name = command;
    m.def(
        command, [name](const py::kwargs& kwargs) { return run_command(name, kwargs); },
        ("`dyncal " + name +
         "` with its command-line options as keyword arguments (data='log.csv', model='eq7', validate_last=0.3, "
         "drop_outliers=True; a list repeats an option). Returns the document --report writes, as a dict, with "
         "every array of numbers as a numpy array, and 'report_text': what the command prints. Raises InputError "
         "with the CLI's one-line message; a failed gate (gate='station.yaml', require=['key=value']) returns the "
         "report, "
         "its 'gate' saying which items failed.")
            .c_str());
  }
}

/// dyncal.Log and dyncal.read_log: logs from arrays or files as the CLI reads them.
void bind_logs(py::module_& m) {
  using dyncal::host::JointLog;
  py::class_<JointLog>(m, "Log",
                       "A joint log: t (S) [s], q, qd, tau (S, N) [rad, rad/s, Nm; m, m/s, N on a prismatic joint]. "
                       "Log(robot, t, q, tau, qd=None) from arrays; dyncal.read_log reads files as the CLI does.")
      .def(py::init(&log_of), py::arg("robot"), py::arg("t"), py::arg("q"), py::arg("tau"), py::arg("qd") = py::none())
      .def_readonly("t", &JointLog::t)
      .def_readonly("q", &JointLog::q)
      .def_readonly("qd", &JointLog::qd)
      .def_readonly("tau", &JointLog::tau)
      .def_readonly("has_qd", &JointLog::has_qd)
      .def_readonly("source", &JointLog::source)
      .def_property_readonly("samples", &JointLog::samples)
      .def_property_readonly("joints", &JointLog::joints)
      .def("__repr__", [](const JointLog& l) {
        return "<dyncal.Log " + l.source + ", " + std::to_string(l.samples()) + " samples, " +
               std::to_string(l.joints()) + " joints>";
      });
  m.def(
      "read_log",
      [](const Robot& r, const py::object& data, const std::string& format, const std::string& columns,
         const std::string& torque_from, bool merge_on_time, bool drop_outliers, const std::string& topic,
         const std::string& effort, const std::string& clock) {
        std::vector<std::string> paths;
        if (py::isinstance<py::str>(data))
          paths.push_back(data.cast<std::string>());
        else
          paths = data.cast<std::vector<std::string>>();
        return read_log(r, paths, format, columns, torque_from, merge_on_time, drop_outliers, topic, effort, clock);
      },
      py::arg("robot"), py::arg("data"), py::arg("format") = "csv", py::arg("columns") = "",
      py::arg("torque_from") = "torque", py::arg("merge_on_time") = false, py::arg("drop_outliers") = false,
      py::arg("topic") = "", py::arg("effort") = "", py::arg("clock") = "header",
      "The log at `data` (a path, or a list of paths stacked as segments) as `dyncal identify --data` reads it "
      "(--format csv|ur-rtde|tx40|ros2-bag, --columns, --torque-from, --merge-on-time, --drop-outliers, the bag "
      "options), checked against the robot's limits. Raises InputError with the CLI's message.");
}

/// dyncal.ParameterSet: a parameter file, read and written.
void bind_parameter_sets(py::module_& m) {
  using dyncal::host::ParameterSet;
  py::class_<ParameterSet>(m, "ParameterSet",
                           "Identified parameters of one robot and model (a `dyncal identify --params` file).")
      .def_static("read", &dyncal::host::read_parameter_file, py::arg("path"),
                  "Reads a parameter file; raises InputError naming what is wrong.")
      .def(
          "write",
          [](const ParameterSet& p, const std::string& path, const std::string& method) {
            dyncal::app::write_json_file(path, dyncal::host::parameter_file_json(p, method), "parameter file");
          },
          py::arg("path"), py::arg("method") = "wls", "Writes the parameter file (all or nothing).")
      .def_readonly("robot", &ParameterSet::robot)
      .def_readonly("model", &ParameterSet::model)
      .def_readonly("source", &ParameterSet::source)
      .def_readonly("names", &ParameterSet::names)
      .def_readonly("values", &ParameterSet::values)
      .def_readonly("std", &ParameterSet::stdev, "NaN where the parameter was not determined")
      .def("__repr__", [](const ParameterSet& p) {
        return "<dyncal.ParameterSet " + p.robot + ", " + p.model + ", " + std::to_string(p.values.size()) +
               " parameters>";
      });
}

/// dyncal.Fit, dyncal.fit and dyncal.predict_log: the library's identification and
/// prediction, bound directly (no command line in between).
void bind_fits(py::module_& m) {
  using dyncal::host::IdentifyResult;
  using dyncal::host::JointLog;
  using dyncal::host::ParameterSet;
  py::class_<IdentifyResult>(m, "Fit", "What dyncal.fit identified (the identify report's content).")
      .def_readonly("robot", &IdentifyResult::robot)
      .def_readonly("method", &IdentifyResult::method)
      .def_readonly("model", &IdentifyResult::model)
      .def_readonly("validation", &IdentifyResult::validation)
      .def_readonly("notes", &IdentifyResult::notes)
      .def_readonly("condition_number", &IdentifyResult::condition_number)
      .def_readonly("samples_used", &IdentifyResult::samples_used)
      // The parameters as identify's parameter set holds them (parameter_set, what --params writes).
      .def_property_readonly("names", [](const IdentifyResult& r) { return dyncal::host::parameter_set(r).names; })
      .def_property_readonly("values", [](const IdentifyResult& r) { return dyncal::host::parameter_set(r).values; })
      .def_property_readonly("std", [](const IdentifyResult& r) { return dyncal::host::parameter_set(r).stdev; })
      .def_property_readonly(
          "bases",
          [](const IdentifyResult& r) {
            std::vector<std::string> v;
            for (const auto& p : r.params) v.push_back(p.basis);
            return v;
          },
          "what each value rests on where the log does not determine it: 'prior', 'held at 0', 'least squares', "
          "'search', 'start', 'sign constraint'; empty where the data determine it (identify.hpp's ParamEstimate)")
      .def_property_readonly("verdicts",
                             [](const IdentifyResult& r) {
                               std::vector<std::string> v;
                               for (const auto& p : r.params) v.push_back(dyncal::host::to_string(p.verdict));
                               return v;
                             })
      .def_property_readonly(
          "joints", [](const IdentifyResult& r) { return metrics_of(r.joints); },
          "the validation's per-joint metrics: rms, rms_tau, relative_rms, r2, e_T_abs, e_T_abs_std (numpy, joint j "
          "at index j - 1)")
      .def("parameter_set", &dyncal::host::parameter_set, "The fit as a ParameterSet (what --params writes).");

  m.def(
      "fit",
      [](const Robot& r, const JointLog& log, const std::string& method, const std::string& model, double cutoff_hz,
         int filter_order, int decimate, int folds, double block_seconds, double validate_last, double prior_std,
         double min_speed, bool sign_constraints, bool friction_per_joint, bool strict, std::uint64_t seed) {
        const auto o =
            identify_options(r, method, model, cutoff_hz, filter_order, decimate, folds, block_seconds, validate_last,
                             prior_std, min_speed, sign_constraints, friction_per_joint, strict, seed);
        py::gil_scoped_release release;
        return dyncal::host::identify(r.description, log, o);
      },
      py::arg("robot"), py::arg("log"), py::arg("method") = "wls", py::arg("model") = "eq7,rotor_inertia,offset",
      py::arg("cutoff_hz") = 20.0, py::arg("filter_order") = 4, py::arg("decimate") = 0, py::arg("folds") = 5,
      py::arg("block_seconds") = 0.5, py::arg("validate_last") = 0.0, py::arg("prior_std") = 0.5,
      py::arg("min_speed") = 0.0, py::arg("sign_constraints") = false, py::arg("friction_per_joint") = false,
      py::arg("strict") = false, py::arg("seed") = 1,
      "Identifies the model from `log` (identify.hpp: the CLI's identify, its options by the same names and "
      "defaults: --method, --model, --cutoff, --filter-order, --decimate, --folds, --block, --validate-last, "
      "--prior-std, --min-speed, --sign-constraints, --friction-per-joint, --strict, --seed). Returns a Fit. "
      "Raises InputError.");
  m.def(
      "predict_log",
      [](const Robot& r, const JointLog& log, const ParameterSet& params, double cutoff_hz, int filter_order,
         int decimate) {
        dyncal::host::IdentifyOptions o;
        o.cutoff_hz = cutoff_hz;
        o.filter_order = filter_order;
        o.decimate = decimate;
        dyncal::host::LogPrediction p;
        {
          py::gil_scoped_release release;
          p = dyncal::host::predict(r.description, log, o, params);
        }
        py::dict d = metrics_of(p.joints);
        d["samples"] = p.samples;
        d["notes"] = p.notes;
        return d;
      },
      py::arg("robot"), py::arg("log"), py::arg("params"), py::arg("cutoff_hz") = 20.0, py::arg("filter_order") = 4,
      py::arg("decimate") = 0,
      "The torque of `log` predicted by `params`, filtered as identify filters (prediction.hpp): per-joint "
      "metrics as numpy arrays (rms, rms_tau, relative_rms, r2, e_T_abs, e_T_abs_std), samples, notes.");
}

}  // namespace

PYBIND11_MODULE(dyncal, m) {
  m.doc() = "dyncal: dynamic calibration of serial robot arms (docs/python.md)";
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const dyncal::host::Interrupted& e) {  // the drive was stopped first (stream_run)
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    } catch (const InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    }
  });

  bind_robot(m);
  bind_commands(m);
  bind_logs(m);
  bind_parameter_sets(m);
  bind_fits(m);
}
