#pragma once
// The source tree the programs were built from, for the files they read from it at run time (the
// shipped robots/, codegen/import_urdf.py).

#include <string>

namespace dyncal::host {

/// The source tree's root, absolute, without a trailing '/'. Compiled into source_tree.cpp alone (the
/// one host source whose compile line names a folder, so that ccache serves the others in a clone in
/// another folder).
std::string source_tree_dir();

}  // namespace dyncal::host
