#include "client_flags.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "server_address.hpp"

namespace primlabel::client::tools {

namespace {

std::string trimmed(std::string text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

}  // namespace

void ConnectionFlags::add_to(CLI::App& app) {
  // A bad address is a usage error at parse time, from the flag or the environment alike.
  const CLI::Validator address(
      [](std::string& value) {
        try {
          value = server_address_with_port(value);
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      },
      "HOST[:PORT]");
  app.add_option(
         "--server", server,
         "Server address HOST:PORT; HOST alone means port " + std::to_string(kDefaultServerPort))
      ->envname("PRIMLABEL_SERVER")
      ->transform(address)
      ->capture_default_str();
  app.add_option("--token-file", token_file,
                 "File holding the bearer token (default: $PRIMLABEL_TOKEN when set)");
  app.add_flag("--tls", tls, "Use TLS with the system's root certificates");
  app.add_option("--tls-ca", tls_ca, "PEM CA certificate to verify the server (implies --tls)");
  app.add_option("--tls-cert", tls_cert, "PEM client certificate, for mutual TLS");
  app.add_option("--tls-key", tls_key, "PEM client private key, for mutual TLS");
  app.add_option("--tls-server-name", tls_server_name, "Expected name in the server certificate");
  app.add_option("--deadline", deadline_s, "Seconds a call may take, retries included")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--retries", retries, "Attempts in all when the server is unavailable")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
}

ClientOptions ConnectionFlags::options() const {
  ClientOptions options;
  options.address = server;
  options.deadline = std::chrono::milliseconds(static_cast<long long>(deadline_s * 1000));
  options.retry_attempts = retries;
  if (tls || !tls_ca.empty() || !tls_cert.empty() || !tls_key.empty())
    options.tls = TlsOptions{tls_ca, tls_cert, tls_key, tls_server_name};
  if (!token_file.empty()) {
    std::ifstream in(token_file);
    std::stringstream text;
    text << in.rdbuf();
    if (!in) throw std::runtime_error(token_file + ": cannot read the token file");
    options.bearer_token = trimmed(text.str());
  } else if (const char* env = std::getenv("PRIMLABEL_TOKEN")) {
    options.bearer_token = trimmed(env);
  }
  return options;
}

}  // namespace primlabel::client::tools
