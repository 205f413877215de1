// canhil/rtdb/config_file.hpp — the RTDB configuration file (AGENTS / ITEM /
// SCHEMA / ASSIGNMENT), as canhil-rtdb-gen reads it. Errors are
// RtdbConfigError: `FILE:LINE: what is wrong; what to do`.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "canhil/base/located_error.hpp"

namespace canhil::rtdb {

/// A mistake in the RTDB configuration: `FILE:LINE: what is wrong; what to do`
/// (no field; `FILE: ...` when it concerns the file as a whole).
class RtdbConfigError : public LocatedError {
 public:
  RtdbConfigError(std::string file, int line, const std::string& message)
      : LocatedError(std::move(file), line, "", message) {}
};

struct ItemDecl {
  std::string name;
  std::string datatype;
  std::string headerfile;  ///< defaults to datatype + ".h"
  int period = 1;
  int line = 0;
};

struct SchemaDecl {
  std::string name;
  std::vector<std::string> shared;
  std::vector<std::string> local;
  int line = 0;
};

struct RtdbConfig {
  std::string file;
  std::vector<std::string> agents;
  std::vector<ItemDecl> items;
  std::vector<SchemaDecl> schemas;
  /// Per agent, the index of its schema.
  std::vector<int> agent_schema;
  /// membership[agent][item]: 1 shared, 0 local, -1 absent.
  std::vector<std::vector<int>> membership;
};

RtdbConfig parse_rtdb_config(const std::string& text, const std::string& file);
RtdbConfig load_rtdb_config(const std::filesystem::path& path);

/// rtdb_user.h: #define of every agent and item id, N_AGENTS, N_ITEMS.
std::string generate_user_header(const RtdbConfig& config);
/// rtdb_config.c: the table the library reads (sizes via sizeof from the headers).
std::string generate_config_source(const RtdbConfig& config);

}  // namespace canhil::rtdb
