#pragma once
// The URI of a drive started by a CTest fixture (tests/drive_fixture.sh): read from its ready file.
#include <cstdlib>
#include <fstream>
#include <string>

inline std::string fixture_drive_uri(const char* env_name) {
  const char* path = std::getenv(env_name);
  if (!path) return "";
  std::ifstream in(path);
  std::string uri;
  std::getline(in, uri);
  return uri;
}
