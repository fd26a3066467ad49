#include "primlabel/rpc/auth.hpp"

#include <grpcpp/security/server_credentials.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace primlabel::rpc {

namespace {

// Compares without an early exit, so the time taken does not tell how much of a guess matched.
bool constant_time_equal(const std::string& a, const std::string& b) {
  unsigned char difference = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < a.size(); ++i)
    difference |= static_cast<unsigned char>(a[i] ^ (i < b.size() ? b[i] : 0));
  return difference == 0;
}

std::string read_pem(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TokenAuth::TokenAuth(std::string token, bool required_for_all, bool insecure_admin)
    : token_(std::move(token)),
      required_for_all_(required_for_all),
      insecure_admin_(insecure_admin) {}

std::optional<service::ServiceError> TokenAuth::check(const grpc::ServerContextBase& context,
                                                      bool admin) const {
  if (admin && token_.empty() && !insecure_admin_)
    return service::ServiceError{service::ErrorCode::kPermissionDenied,
                                 "admin RPCs are disabled: this server has no token; start it with "
                                 "--token-file (or PRIMLABEL_TOKEN) to require one, or with "
                                 "--insecure-admin to allow them without one"};
  if (token_.empty() || (!admin && !required_for_all_)) return std::nullopt;
  const auto& metadata = context.client_metadata();
  auto found = metadata.find("authorization");
  if (found == metadata.end())
    return service::ServiceError{service::ErrorCode::kUnauthenticated,
                                 std::string(admin ? "admin RPCs" : "this server") +
                                     " require an 'authorization: Bearer <token>' header"};
  const std::string value(found->second.data(), found->second.size());
  const std::string prefix = "Bearer ";
  if (value.compare(0, prefix.size(), prefix) != 0 ||
      !constant_time_equal(value.substr(prefix.size()), token_))
    return service::ServiceError{service::ErrorCode::kUnauthenticated,
                                 "the bearer token is not valid"};
  return std::nullopt;
}

std::shared_ptr<grpc::ServerCredentials> server_credentials(const TlsFiles& files) {
  if (files.cert.empty()) return grpc::InsecureServerCredentials();
  grpc::SslServerCredentialsOptions options(
      files.client_ca.empty() ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                              : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  options.pem_key_cert_pairs.push_back({read_pem(files.key), read_pem(files.cert)});
  if (!files.client_ca.empty()) options.pem_root_certs = read_pem(files.client_ca);
  return grpc::SslServerCredentials(options);
}

}  // namespace primlabel::rpc
