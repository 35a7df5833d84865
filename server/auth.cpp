#include "server/auth.h"

#include <google/protobuf/message_lite.h>
#include <grpc/grpc.h>
#include <grpc/grpc_security_constants.h>
#include <grpcpp/security/auth_context.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace penumbra::farm {

namespace {

constexpr size_t kMinTokenLength = 16;

std::vector<unsigned char> sha256(std::string_view text) {
  std::vector<unsigned char> digest(32);
  unsigned int size = 0;
  if (EVP_Digest(text.data(), text.size(), digest.data(), &size, EVP_sha256(), nullptr) != 1 ||
      size != digest.size())
    throw std::runtime_error("SHA-256 failed");
  return digest;
}

bool starts_with(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

std::optional<Role> parse_role(std::string_view text) {
  if (text == "client") return Role::client;
  if (text == "worker") return Role::worker;
  if (text == "admin") return Role::admin;
  if (text == "viewer") return Role::viewer;
  return std::nullopt;
}

// Decisions of the calls in flight, by server context (see call_authorization).
struct CallRegistry {
  std::mutex mutex;
  std::unordered_map<const grpc::ServerContextBase*, CallAuthorization> calls;
};

CallRegistry& registry() {
  static CallRegistry instance;
  return instance;
}

class AuthInterceptor final : public grpc::experimental::Interceptor {
 public:
  AuthInterceptor(grpc::experimental::ServerRpcInfo* info, const AuthPolicy& policy)
      : info_(info), method_(info->method() ? info->method() : ""), policy_(policy) {
    // Fail closed: until the metadata has been checked, the call counts as refused.
    CallAuthorization pending;
    pending.status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "not authenticated yet");
    std::lock_guard lock(registry().mutex);
    registry().calls[info_->server_context()] = pending;
    published_ = true;
  }

  ~AuthInterceptor() override {
    if (!published_) return;
    std::lock_guard lock(registry().mutex);
    registry().calls.erase(info_->server_context());
  }

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    using grpc::experimental::InterceptionHookPoints;
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::POST_RECV_INITIAL_METADATA))
      decide(*methods->GetRecvInitialMetadata());
    // A refused call's request is emptied before any handler runs: a handler that does not
    // consult call_authorization still cannot act on what the caller sent.
    if (denied_ && methods->QueryInterceptionHookPoint(InterceptionHookPoints::POST_RECV_MESSAGE) &&
        starts_with(method_, "/penumbra.")) {
      if (void* message = methods->GetRecvMessage())
        static_cast<google::protobuf::MessageLite*>(message)->Clear();
    }
    methods->Proceed();
  }

 private:
  void decide(const std::multimap<grpc::string_ref, grpc::string_ref>& metadata) {
    std::optional<std::string_view> authorization;
    auto found = metadata.find("authorization");
    if (found != metadata.end())
      authorization = std::string_view(found->second.data(), found->second.size());
    grpc::ServerContextBase* context = info_->server_context();
    bool certificate = false;
    if (policy_.workers_need_client_certificate) {
      // Present only when the TLS layer verified the client's certificate against the CA.
      std::shared_ptr<const grpc::AuthContext> peer = context->auth_context();
      certificate = peer && !peer->FindPropertyValues(GRPC_X509_PEM_CERT_PROPERTY_NAME).empty();
    }
    CallAuthorization decision = authorize_call(policy_, method_, authorization, certificate);
    denied_ = !decision.status.ok();
    {
      std::lock_guard lock(registry().mutex);
      registry().calls[context] = decision;
    }
    if (!denied_) return;
    spdlog::warn("refused {} from {}: {}", method_, context->peer(),
                 decision.status.error_message());
    // Ends the call with this status now (sent to the client as its trailers).
    grpc_call_cancel_with_status(context->c_call(),
                                 static_cast<grpc_status_code>(decision.status.error_code()),
                                 decision.status.error_message().c_str(), nullptr);
  }

  grpc::experimental::ServerRpcInfo* info_;
  std::string method_;
  const AuthPolicy& policy_;  // the factory's, which outlives the server and its calls
  bool published_ = false;
  bool denied_ = false;
};

}  // namespace

std::string role_name(Role role) {
  switch (role) {
    case Role::client:
      return "client";
    case Role::worker:
      return "worker";
    case Role::admin:
      return "admin";
    case Role::viewer:
      return "viewer";
  }
  return "unknown";
}

TokenTable TokenTable::parse(std::string_view text, std::string_view source_name) {
  TokenTable table;
  std::vector<std::vector<unsigned char>> digests;
  std::istringstream lines{std::string(text)};
  std::string line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    if (size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    std::string role_text, name, token, extra;
    if (!(fields >> role_text)) continue;  // blank or comment
    auto where = [&] { return std::string(source_name) + ":" + std::to_string(number) + ": "; };
    if (!(fields >> name >> token) || (fields >> extra))
      throw std::runtime_error(where() + "expected \"role name token\"");
    std::optional<Role> role = parse_role(role_text);
    if (!role)
      throw std::runtime_error(where() + "unknown role \"" + role_text +
                               "\" (client, worker, admin or viewer)");
    if (token.size() < kMinTokenLength)
      throw std::runtime_error(where() + "the token of " + name + " is shorter than " +
                               std::to_string(kMinTokenLength) + " characters");
    Entry entry{{name, *role}, sha256(token)};
    for (const Entry& other : table.entries_)
      if (other.digest == entry.digest)
        throw std::runtime_error(where() + "the token of " + name + " is also the token of " +
                                 other.principal.name);
    table.entries_.push_back(std::move(entry));
  }
  return table;
}

TokenTable TokenTable::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read the tokens file " + path);
  std::ostringstream text;
  text << in.rdbuf();
  TokenTable table = parse(text.str(), path);
  if (table.size() == 0) throw std::runtime_error("the tokens file " + path + " has no tokens");
  return table;
}

std::optional<Principal> TokenTable::find(std::string_view token) const {
  // Fixed-size digests compared with CRYPTO_memcmp against every entry: neither the position of
  // the first differing byte nor the matching entry changes the work done.
  std::vector<unsigned char> digest = sha256(token);
  const Entry* match = nullptr;
  for (const Entry& entry : entries_) {
    bool equal = CRYPTO_memcmp(entry.digest.data(), digest.data(), digest.size()) == 0;
    if (equal && !match) match = &entry;
  }
  if (!match) return std::nullopt;
  return match->principal;
}

std::optional<Role> required_role(std::string_view method) {
  if (starts_with(method, "/grpc.health.v1.Health/") ||
      starts_with(method, "/grpc.reflection.v1alpha.ServerReflection/") ||
      starts_with(method, "/grpc.reflection.v1.ServerReflection/"))
    return std::nullopt;
  if (starts_with(method, "/penumbra.v1.Jobs/") || starts_with(method, "/penumbra.v1.Batches/"))
    return Role::client;
  if (starts_with(method, "/penumbra.v1.Workers/")) return Role::worker;
  return Role::admin;
}

bool role_allows(Role held, Role required) {
  return held == Role::admin || held == required;
}

std::optional<std::string_view> bearer_token(std::string_view authorization) {
  constexpr std::string_view kScheme = "bearer";
  if (authorization.size() <= kScheme.size()) return std::nullopt;
  for (size_t i = 0; i < kScheme.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(authorization[i])) != kScheme[i])
      return std::nullopt;
  std::string_view rest = authorization.substr(kScheme.size());
  if (rest.front() != ' ') return std::nullopt;
  size_t begin = rest.find_first_not_of(' ');
  if (begin == std::string_view::npos) return std::nullopt;
  std::string_view token = rest.substr(begin);
  while (!token.empty() && (token.back() == ' ' || token.back() == '\t')) token.remove_suffix(1);
  if (token.empty()) return std::nullopt;
  return token;
}

CallAuthorization authorize_call(const AuthPolicy& policy, std::string_view method,
                                 std::optional<std::string_view> authorization,
                                 bool verified_client_certificate) {
  std::optional<Role> required = required_role(method);
  CallAuthorization result;
  std::optional<std::string_view> token;
  if (authorization) token = bearer_token(*authorization);
  if (token && policy.tokens) result.principal = policy.tokens->find(*token);
  if (!required) return result;  // open method
  if (policy.workers_need_client_certificate && starts_with(method, "/penumbra.v1.Workers/") &&
      !verified_client_certificate) {
    result.status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                                 "this coordinator requires mutual TLS for workers: connect with a "
                                 "client certificate signed by its --tls-client-ca "
                                 "(--tls-cert, --tls-key)");
    return result;
  }
  if (!policy.tokens) return result;  // tokens off
  if (!authorization) {
    result.status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                                 "this coordinator requires a token: send \"authorization: Bearer "
                                 "<token>\" (--token, --token-file or PENUMBRA_TOKEN)");
  } else if (!token) {
    result.status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                                 "the authorization header is not \"Bearer <token>\"");
  } else if (!result.principal) {
    result.status = grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "unknown token");
  } else if (!role_allows(result.principal->role, *required)) {
    result.status = grpc::Status(
        grpc::StatusCode::PERMISSION_DENIED,
        "\"" + result.principal->name + "\" has role " + role_name(result.principal->role) + "; " +
            std::string(method) + " needs role " + role_name(*required) + " or admin");
  }
  return result;
}

std::optional<CallAuthorization> call_authorization(const grpc::ServerContextBase* context) {
  std::lock_guard lock(registry().mutex);
  auto found = registry().calls.find(context);
  if (found == registry().calls.end()) return std::nullopt;
  return found->second;
}

CallContext call_context_of(const grpc::ServerContextBase* context) {
  std::optional<CallAuthorization> authorization = call_authorization(context);
  if (!authorization || !authorization->principal) return CallContext::internal();
  const Principal& principal = *authorization->principal;
  return principal.role == Role::admin ? CallContext::of_admin(principal.name)
                                       : CallContext::of_client(principal.name);
}

HttpAuthorization authorize_http(const TokenTable* tokens,
                                 std::optional<std::string_view> authorization_header,
                                 std::optional<std::string_view> token_parameter) {
  HttpAuthorization result;
  if (!tokens) return result;  // authentication off
  auto refuse = [&](int status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.caller = CallContext::of_client(std::string());
    result.sees_farm = false;
    return result;
  };
  std::optional<std::string_view> token;
  if (authorization_header) {
    token = bearer_token(*authorization_header);
    if (!token) return refuse(401, "the Authorization header is not \"Bearer <token>\"");
  } else if (token_parameter) {
    token = *token_parameter;
    result.token_from_query = true;
  }
  if (!token)
    return refuse(401,
                  "this coordinator requires a token: send \"Authorization: Bearer <token>\", or "
                  "add ?token=<token> to the address in a browser");
  result.principal = tokens->find(*token);
  if (!result.principal) return refuse(401, "unknown token");
  const Principal& who = *result.principal;
  switch (who.role) {
    case Role::worker:
      return refuse(403, "\"" + who.name +
                             "\" has role worker, which has no access to the web side (client, "
                             "viewer or admin)");
    case Role::client:
      result.caller = CallContext::of_client(who.name);
      result.sees_farm = false;
      break;
    case Role::viewer:
    case Role::admin:
      result.caller = CallContext::of_admin(who.name);
      result.sees_farm = true;
      break;
  }
  return result;
}

grpc::experimental::Interceptor* AuthInterceptorFactory::CreateServerInterceptor(
    grpc::experimental::ServerRpcInfo* info) {
  return new AuthInterceptor(info, policy_);
}

}  // namespace penumbra::farm
