#pragma once
// Option checks shared by the client's commands.

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdlib>
#include <string>

namespace penumbra {

// A seed is a 64-bit unsigned integer written in decimal: "-1" or 2^64 are refused (a plain
// conversion would wrap them to 2^64 - 1 without a word).
inline CLI::Validator seed_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::string refusal =
            "the seed is an integer in [0, 18446744073709551615], got \"" + text + "\"";
        if (text.empty() || text.size() > 20) return refusal;
        for (char c : text)
          if (c < '0' || c > '9') return refusal;
        errno = 0;
        std::strtoull(text.c_str(), nullptr, 10);
        return errno == ERANGE ? refusal : std::string();
      },
      "UINT64");
}

}  // namespace penumbra
