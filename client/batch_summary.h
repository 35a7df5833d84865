#pragma once
// The table `penumbra batch run` and `batch fetch` print from a result folder's batch.json
// (penumbra/batch-result@1): one line per equal-time or spp run, its spp, compute seconds and
// MRSE of the full image and every region. Every column is as wide as its widest entry or
// header: no header or label is cut ("MRSE penumbra-edge1").

#include <nlohmann/json.hpp>
#include <string>

namespace penumbra {

std::string batch_summary_table(const nlohmann::json& index);

}  // namespace penumbra
