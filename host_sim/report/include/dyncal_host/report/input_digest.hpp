#pragma once
// What a report read, so that a page or a station's record names its inputs beyond their paths.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace dyncal::host {

/// [{path, bytes, sha256}] of each input: a file, or every regular file of a folder (a vendor log
/// folder), sorted by path. SHA-256 (FIPS 180-4) by OpenSSL's libcrypto, hex. Throws InputError when a
/// file cannot be read.
nlohmann::json input_digests(const std::vector<std::string>& paths);

/// `bytes` in base64 (RFC 4648; OpenSSL's EVP_EncodeBlock), for data: URIs.
std::string base64(const std::string& bytes);

}  // namespace dyncal::host
