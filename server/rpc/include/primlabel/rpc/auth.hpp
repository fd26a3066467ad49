#pragma once
// Who may call what: a bearer token ("authorization: Bearer <token>") on admin RPCs, and
// optionally on every RPC; TLS or mutual-TLS server credentials from PEM files.

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_context.h>

#include <memory>
#include <optional>
#include <string>

#include "primlabel/service/service_error.hpp"

namespace primlabel::rpc {

class TokenAuth {
 public:
  // An empty token means no checks on non-admin RPCs; admin RPCs are then refused unless
  // `insecure_admin` allows them (anyone who reaches the port could unload every model).
  TokenAuth(std::string token, bool required_for_all, bool insecure_admin = false);

  // Nothing, or UNAUTHENTICATED saying what is missing, or PERMISSION_DENIED naming the flags
  // that enable admin RPCs. `admin` RPCs need the token whenever one is configured; the others
  // only with required_for_all. Any kind of server context.
  std::optional<service::ServiceError> check(const grpc::ServerContextBase& context,
                                             bool admin) const;

  bool enabled() const { return !token_.empty(); }
  bool admin_open() const { return token_.empty() && insecure_admin_; }

 private:
  std::string token_;
  bool required_for_all_;
  bool insecure_admin_;
};

struct TlsFiles {
  std::string cert, key;  // PEM; both empty = plaintext
  std::string client_ca;  // PEM; non-empty = clients must present a certificate it signed
};

// Insecure credentials without a certificate; throws std::runtime_error for unreadable files.
std::shared_ptr<grpc::ServerCredentials> server_credentials(const TlsFiles& files);

}  // namespace primlabel::rpc
