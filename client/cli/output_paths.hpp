// Outputs checked before a command's work, so that one that cannot be written fails the command at once rather
// than after its pathlines. Nothing is made here: folders are made when the outputs are written, and that write's
// own error stays the last word (a check passed here can still fail then).
#pragma once

#include <string>

namespace texwarp::cli {

// A file output's folder exists, is a folder and may be written in. std::runtime_error "FLAG PATH: cannot write
// there (FOLDER does not exist | is not a folder | …)". An empty path is no output: nothing to check.
void check_output_file(const std::string& flag, const std::string& path);

// An output folder (made with its missing parents when written) could be made: its deepest level that exists is a
// folder that may be written in, or the folder itself. std::runtime_error "FLAG FOLDER: cannot make the folder (…)",
// in create_directories' words: File exists (a file, or a link to nothing, in its place), Not a directory (one on
// its way), Permission denied. An empty folder is none: nothing to check.
void check_output_folder(const std::string& flag, const std::string& folder);

}  // namespace texwarp::cli
