// Validators for command-line values whose CLI11 messages would not name the fix: a missing
// file or directory, and a ZeroMQ endpoint written without its scheme. Each returns a CLI11
// Validator; a failure becomes one `pamdp: error: --OPTION: <message>` line (app/main.cpp).
// Cost: a stat() or a string compare, at parse time only.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>

namespace pamdp::app {

// A file that must exist; `hint` says where such files are (e.g. "trained agents: models/*.ckpt").
inline CLI::Validator existing_file(const std::string& hint) {
  return CLI::Validator(
      [hint](std::string& path) -> std::string {
        std::error_code ec;
        if (std::filesystem::is_regular_file(path, ec)) {
          return {};
        }
        if (std::filesystem::is_directory(path, ec)) {
          return "'" + path + "' is a directory, not a file; " + hint;
        }
        return "no file '" + path + "'; " + hint;
      },
      "FILE");
}

// A directory that must exist; `hint` says which directories fit.
inline CLI::Validator existing_directory(const std::string& hint) {
  return CLI::Validator(
      [hint](std::string& path) -> std::string {
        std::error_code ec;
        if (std::filesystem::is_directory(path, ec)) {
          return {};
        }
        return (std::filesystem::exists(path, ec) ? "'" + path + "' is not a directory; "
                                                  : "no directory '" + path + "'; ") +
               hint;
      },
      "DIR");
}

// A ZeroMQ endpoint: tcp://HOST:PORT (or ipc://, inproc://). "127.0.0.1:5555" without the scheme
// is answered with the endpoint it probably meant.
inline CLI::Validator zmq_endpoint() {
  return CLI::Validator(
      [](std::string& endpoint) -> std::string {
        for (const char* scheme : {"tcp://", "ipc://", "inproc://"}) {
          if (endpoint.rfind(scheme, 0) == 0) {
            return {};
          }
        }
        const size_t sep = endpoint.find("://");
        const std::string rest = sep == std::string::npos ? endpoint : endpoint.substr(sep + 3);
        return "'" + endpoint + "' is not an endpoint: write tcp://HOST:PORT, e.g. tcp://" +
               (rest.find(':') != std::string::npos ? rest : "127.0.0.1:5555");
      },
      "ENDPOINT");
}

}  // namespace pamdp::app
