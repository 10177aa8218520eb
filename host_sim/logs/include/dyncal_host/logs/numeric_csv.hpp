#pragma once

#include <Eigen/Core>
#include <istream>
#include <map>
#include <string>
#include <vector>

namespace dyncal::host {

/// A delimited file of numbers with one header line. The header sets the separator: a comma, else
/// a semicolon, else a tab, else spaces (runs of spaces or tabs separate; loggers that align columns
/// or write the RTDE recorder's default). Fields are trimmed of spaces.
struct NumericCsv {
  std::vector<std::string> header;  ///< column names, surrounding spaces removed
  Eigen::MatrixXd values;           ///< rows = data lines
};

/// Reads `path`. Throws InputError on: unreadable file, empty file, a line with a different number
/// of fields than the header, a field that is not a number or is NaN/infinite (message names the
/// file, line and column).
NumericCsv read_numeric_csv(const std::string& path);

/// Parses CSV text from `in` as read_numeric_csv does; `name` stands for the file in messages.
/// Throws InputError as read_numeric_csv (the fuzz target tests/fuzz/fuzz_numeric_csv.cpp).
NumericCsv parse_numeric_csv(std::istream& in, const std::string& name);

/// `field` without its leading and trailing spaces, tabs and carriage returns (a CRLF file's line
/// end): how a header name, a value or a column-map entry is read.
std::string trim_field(const std::string& field);

/// Each of `csv`'s columns by name: its index. Throws InputError naming `path` and a column name
/// the header gives twice.
std::map<std::string, Eigen::Index> column_index(const NumericCsv& csv, const std::string& path);

}  // namespace dyncal::host
