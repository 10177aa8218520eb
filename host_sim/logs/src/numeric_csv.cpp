#include "dyncal_host/logs/numeric_csv.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

/// The header's separator: a comma, else a semicolon, else a tab, else ' ' (runs of spaces or tabs
/// separate, as in a space-aligned export).
char separator_of(const std::string& header) {
  for (const char c : {',', ';', '\t'}) {
    if (header.find(c) != std::string::npos) return c;
  }
  return ' ';
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  if (sep == ' ') {
    std::string::size_type start = line.find_first_not_of(" \t\r");
    while (start != std::string::npos) {
      const auto end = line.find_first_of(" \t\r", start);
      out.push_back(line.substr(start, end == std::string::npos ? std::string::npos : end - start));
      start = end == std::string::npos ? end : line.find_first_not_of(" \t\r", end);
    }
    return out;
  }
  std::string::size_type start = 0;
  while (true) {
    const auto at = line.find(sep, start);
    out.push_back(trim_field(line.substr(start, at == std::string::npos ? std::string::npos : at - start)));
    if (at == std::string::npos) break;
    start = at + 1;
  }
  return out;
}

}  // namespace

NumericCsv read_numeric_csv(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError("'" + path + "' is a directory, not a CSV file");
  std::ifstream in(path);
  if (!in) throw InputError("cannot read '" + path + "'");
  return parse_numeric_csv(in, path);
}

NumericCsv parse_numeric_csv(std::istream& in, const std::string& path) {
  NumericCsv csv;
  std::string line;
  if (!std::getline(in, line) || trim_field(line).empty()) throw InputError(path + ": empty file (no header line)");
  // A UTF-8 byte-order mark (spreadsheet exports) is not part of the first column's name.
  if (line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
  const char sep = separator_of(line);
  csv.header = split(line, sep);
  const size_t cols = csv.header.size();
  // Rows are read into blocks of kBlockRows and copied into the matrix block by block, each freed
  // once copied: the peak is the table twice, not a growing vector's reallocations (issue 23).
  constexpr size_t kBlockRows = 8192;
  std::vector<std::vector<double>> blocks;
  size_t rows = 0;
  long line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (trim_field(line).empty()) continue;
    const auto fields = split(line, sep);
    if (fields.size() != cols) {
      throw InputError(path + ":" + std::to_string(line_no) + ": " + std::to_string(fields.size()) +
                       " fields, header has " + std::to_string(cols));
    }
    if (rows % kBlockRows == 0) {
      blocks.emplace_back();
      blocks.back().reserve(kBlockRows * cols);
    }
    ++rows;
    for (size_t c = 0; c < cols; ++c) {
      const std::string& f = fields[c];
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(f.c_str(), &end);
      if (f.empty() || end != f.c_str() + f.size()) {
        throw InputError(path + ":" + std::to_string(line_no) + ": column '" + excerpt(csv.header[c]) + "': '" +
                         excerpt(f) + "' is not a number");
      }
      // ERANGE: overflow gives +-HUGE_VAL (refused below as non-finite, with its own words);
      // underflow (1e-320) gives the nearest subnormal or zero, a faithful reading of the text.
      if (errno == ERANGE && std::isinf(v)) {
        throw InputError(path + ":" + std::to_string(line_no) + ": column '" + excerpt(csv.header[c]) + "': '" +
                         excerpt(f) + "' is beyond the range of a double");
      }
      if (!std::isfinite(v)) {
        throw InputError(path + ":" + std::to_string(line_no) + ": column '" + excerpt(csv.header[c]) +
                         "': non-finite value '" + excerpt(f) + "'");
      }
      blocks.back().push_back(v);
    }
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  csv.values.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  Eigen::Index row = 0;
  for (std::vector<double>& block : blocks) {
    const Eigen::Index n = static_cast<Eigen::Index>(block.size() / cols);
    csv.values.middleRows(row, n) = Eigen::Map<const RowMajor>(block.data(), n, static_cast<Eigen::Index>(cols));
    row += n;
    std::vector<double>().swap(block);
  }
  return csv;
}

std::string trim_field(const std::string& field) {
  const auto b = field.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = field.find_last_not_of(" \t\r");
  return field.substr(b, e - b + 1);
}

std::map<std::string, Eigen::Index> column_index(const NumericCsv& csv, const std::string& path) {
  std::map<std::string, Eigen::Index> col;
  for (size_t i = 0; i < csv.header.size(); ++i) {
    if (!col.emplace(csv.header[i], static_cast<Eigen::Index>(i)).second)
      throw InputError(path + ": duplicate column '" + excerpt(csv.header[i]) + "'");
  }
  return col;
}

}  // namespace dyncal::host
