#pragma once
// Reading a JSON file with the one-line errors every command gives.

#include <nlohmann/json.hpp>
#include <string>

namespace dyncal::host {

/// The JSON document in the file at `path`. Throws InputError: "cannot read '<path>'" when the file
/// cannot be opened, "<path>: invalid JSON: <parser message>" when it does not parse.
nlohmann::json read_json_file(const std::string& path);

/// A parser's message as one printable ASCII line: nlohmann-json quotes the bytes it last read, and
/// a file in another encoding (UTF-16) would put raw bytes on the terminal; each byte outside
/// printable ASCII becomes \xNN.
std::string printable_message(const std::string& message);

}  // namespace dyncal::host
