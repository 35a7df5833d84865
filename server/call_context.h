#pragma once
// Who a call to the coordinator (server/coordinator.h) or the batch manager is made for.
//
// The gRPC services build one per call from the auth interceptor's decision (server/auth.h,
// call_context_of): a client sees, watches, cancels and fetches only the jobs and batches it owns
// (JobSpec.owner / BatchStatus.owner, the token's name); anything else is NOT_FOUND with the same
// message as an id that does not exist, so a client cannot learn which ids other clients hold.
// Admins, the coordinator's own callers (the batch manager, the HTTP side, tests) and every caller
// while authentication is off (no names to tell apart) see every job.

#include <string>
#include <utility>

namespace penumbra::farm {

struct CallContext {
  // The caller's name: the owner of what it submits. Empty for the coordinator's own calls and
  // with authentication off.
  std::string client;
  bool sees_every_job = false;

  // The coordinator's own callers (and authentication off): every job, owner left as given.
  static CallContext internal() { return {std::string(), true}; }
  // An authenticated client: its own jobs only.
  static CallContext of_client(std::string name) { return {std::move(name), false}; }
  // An authenticated admin: every job; what it submits is its own.
  static CallContext of_admin(std::string name) { return {std::move(name), true}; }

  bool may_see(const std::string& owner) const { return sees_every_job || owner == client; }
};

}  // namespace penumbra::farm
