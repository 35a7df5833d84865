#pragma once
// The words the client, the status pages and the dashboard print for a job's or a batch's state.

#include <string>

#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm {

std::string state_name(v1::JobState state);
std::string state_name(v1::BatchState state);

}  // namespace penumbra::farm
