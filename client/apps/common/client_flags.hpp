#pragma once
// The connection flags every client tool shares (--server, else $PRIMLABEL_SERVER; --token-file,
// --tls-*, --deadline, --retries) and their translation into ClientOptions.

#include <CLI/CLI.hpp>
#include <string>

#include "primlabel/client/client.hpp"

namespace primlabel::client::tools {

struct ConnectionFlags {
  std::string server = "127.0.0.1:50051";
  std::string token_file;
  std::string tls_ca, tls_cert, tls_key, tls_server_name;
  bool tls = false;
  double deadline_s = 60;
  int retries = 4;

  // Adds the flags to `app`.
  void add_to(CLI::App& app);
  // ClientOptions from the flags; the token comes from --token-file, else $PRIMLABEL_TOKEN.
  // Throws std::runtime_error naming the file when the token file cannot be read.
  ClientOptions options() const;
};

}  // namespace primlabel::client::tools
