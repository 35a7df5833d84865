#include "proto/support/state_names.h"

namespace penumbra::farm {

std::string state_name(v1::JobState state) {
  switch (state) {
    case v1::JOB_STATE_QUEUED:
      return "queued";
    case v1::JOB_STATE_RUNNING:
      return "running";
    case v1::JOB_STATE_DONE:
      return "done";
    case v1::JOB_STATE_FAILED:
      return "failed";
    case v1::JOB_STATE_CANCELLED:
      return "cancelled";
    default:
      return "unknown";
  }
}

std::string state_name(v1::BatchState state) {
  switch (state) {
    case v1::BATCH_STATE_REFERENCE:
      return "reference";
    case v1::BATCH_STATE_CALIBRATING:
      return "calibrating";
    case v1::BATCH_STATE_RUNNING:
      return "running";
    case v1::BATCH_STATE_DONE:
      return "done";
    case v1::BATCH_STATE_FAILED:
      return "failed";
    case v1::BATCH_STATE_CANCELLED:
      return "cancelled";
    default:
      return "unknown";
  }
}

}  // namespace penumbra::farm
