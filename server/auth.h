#pragma once
// Token authentication with roles for the coordinator's gRPC API.
//
// A caller presents "authorization: Bearer <token>" metadata. Tokens come from a file of lines
// "role name token" (role: client, worker, admin or viewer; '#' starts a comment). The roles:
//   client — every method of /penumbra.v1.Jobs/ and /penumbra.v1.Batches/;
//   worker — every method of /penumbra.v1.Workers/;
//   admin  — both;
//   viewer — no gRPC method: the web side only (authorize_http), where it reads everything.
// Health checking (/grpc.health.v1.Health/) and server reflection stay open; any other method
// needs admin. No token or an unknown one: UNAUTHENTICATED; a known token of the wrong role:
// PERMISSION_DENIED. Tokens are compared in constant time (SHA-256 digests compared with
// CRYPTO_memcmp against every entry) and never logged.
//
// Mutual TLS for workers (optional): with workers_need_client_certificate, the Workers methods
// also need a client certificate the TLS layer verified against --tls-client-ca (UNAUTHENTICATED
// without one); clients may still connect without a certificate.
//
// AuthInterceptorFactory enforces this for every call (install it through
// CoordinatorServerOptions::configure; it works with and without TLS). gRPC's C++ server
// interceptors cannot answer a call themselves, so a refused call is cancelled with its status
// (the client receives exactly that code and message), its request message is cleared before any
// handler sees it, and the decision is published for the handlers: call_authorization(context)
// lets a handler return at once, and names the caller (JobSpec.owner).

#include <grpcpp/server_context.h>
#include <grpcpp/support/server_interceptor.h>
#include <grpcpp/support/status.h>

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/call_context.h"

namespace penumbra::farm {

enum class Role { client, worker, admin, viewer };

std::string role_name(Role role);

struct Principal {
  std::string name;
  Role role = Role::client;
};

class TokenTable {
 public:
  // Parses the token file's text. Throws std::runtime_error naming the source and line (never
  // the token) for a malformed line, an unknown role, a token shorter than 16 characters, or a
  // token given twice. One name may hold several tokens (e.g. a client and an admin token).
  static TokenTable parse(std::string_view text, std::string_view source_name);
  static TokenTable load(const std::string& path);

  // The principal holding `token`; empty for an unknown token. The time taken does not depend on
  // which entry matches nor on how much of a stored token the presented one shares.
  std::optional<Principal> find(std::string_view token) const;
  size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    Principal principal;
    std::vector<unsigned char> digest;  // SHA-256 of the token
  };
  std::vector<Entry> entries_;
};

// Which role a method needs: nullopt for open methods (health, reflection).
// Jobs and Batches: Role::client; Workers: Role::worker; anything else: Role::admin.
std::optional<Role> required_role(std::string_view method);
// Admin holds every role.
bool role_allows(Role held, Role required);

// The token in an "authorization" header value ("Bearer <token>", scheme case-insensitive).
std::optional<std::string_view> bearer_token(std::string_view authorization);

struct AuthPolicy {
  std::shared_ptr<const TokenTable> tokens;      // null: no tokens checked (authentication off)
  bool workers_need_client_certificate = false;  // mutual TLS for /penumbra.v1.Workers/
};

struct CallAuthorization {
  grpc::Status status;                 // OK, UNAUTHENTICATED or PERMISSION_DENIED
  std::optional<Principal> principal;  // the caller, when its token is known
};

// The decision for a call of `method` carrying `authorization` (nullopt: no such header) over a
// connection with or without a verified client certificate.
CallAuthorization authorize_call(const AuthPolicy& policy, std::string_view method,
                                 std::optional<std::string_view> authorization,
                                 bool verified_client_certificate);

// The decision the interceptor made for the call of `context`; nullopt when the server has no
// auth interceptor (authentication off). Valid from before the handler runs until the call ends.
std::optional<CallAuthorization> call_authorization(const grpc::ServerContextBase* context);

// The caller of `context` for the coordinator (server/call_context.h): an authenticated client
// sees its own jobs, an admin every job; without a known principal (authentication off) the
// call sees every job.
CallContext call_context_of(const grpc::ServerContextBase* context);

// The web side (server/http_frontend.h). A request presents its token in an
// "Authorization: Bearer <token>" header or, for a browser that follows links and loads images,
// in a "token" query parameter (the header wins when both are given). With authentication on:
//   no token, a malformed header or an unknown token: 401;
//   a worker token: 403 (workers have nothing to read there);
//   a client token: 200, seeing its own jobs and batches only (another's are 404 like an unknown
//     id), and not the farm-wide pages (/metrics): 403;
//   a viewer or admin token: 200, seeing everything.
// With authentication off (no tokens) every request sees everything.
struct HttpAuthorization {
  int status = 200;     // 200, 401 or 403
  std::string message;  // why not (never the token)
  std::optional<Principal> principal;
  CallContext caller = CallContext::internal();  // whose jobs and batches it sees
  bool sees_farm = true;                         // viewer, admin or authentication off
  bool token_from_query = false;                 // the token came in the "token" parameter
};
HttpAuthorization authorize_http(const TokenTable* tokens,
                                 std::optional<std::string_view> authorization_header,
                                 std::optional<std::string_view> token_parameter);

class AuthInterceptorFactory final : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit AuthInterceptorFactory(AuthPolicy policy) : policy_(std::move(policy)) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override;

 private:
  AuthPolicy policy_;
};

}  // namespace penumbra::farm
