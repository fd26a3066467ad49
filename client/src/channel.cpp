#include "channel.hpp"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/channel_arguments.h>

#include <fstream>
#include <sstream>

namespace primlabel::client {

namespace {

std::string read_pem(const std::string& path, const char* what) {
  if (path.empty()) return {};
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  if (!in || text.str().empty())
    throw ClientError(grpc::StatusCode::INVALID_ARGUMENT,
                      path + ": cannot read the " + what + " file");
  return text.str();
}

int ms(std::chrono::milliseconds d) { return static_cast<int>(d.count()); }

}  // namespace

std::shared_ptr<grpc::Channel> make_channel(const ClientOptions& options) {
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, ms(options.keepalive_time));
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, ms(options.keepalive_timeout));
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS,
              options.keepalive_permit_without_calls ? 1 : 0);
  args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 100);
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 100);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, ms(options.max_reconnect_backoff));
  args.SetMaxReceiveMessageSize(options.max_receive_message_bytes);
  // The client retries itself (with the caller's policy); gRPC's own retries would multiply it.
  args.SetInt(GRPC_ARG_ENABLE_RETRIES, 0);

  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (options.tls) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = read_pem(options.tls->ca_file, "CA certificate");
    ssl.pem_cert_chain = read_pem(options.tls->cert_file, "client certificate");
    ssl.pem_private_key = read_pem(options.tls->key_file, "client key");
    if (ssl.pem_cert_chain.empty() != ssl.pem_private_key.empty())
      throw ClientError(grpc::StatusCode::INVALID_ARGUMENT,
                        "mutual TLS needs both a client certificate and its key");
    if (!options.tls->server_name_override.empty())
      args.SetSslTargetNameOverride(options.tls->server_name_override);
    credentials = grpc::SslCredentials(ssl);
  } else {
    credentials = grpc::InsecureChannelCredentials();
  }
  return grpc::CreateCustomChannel(options.address, credentials, args);
}

}  // namespace primlabel::client
