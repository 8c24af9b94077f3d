// The helper thread of a registration's mini-batch queries (src/helper_thread.hpp).
#include "helper_thread.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace sgdicp {
namespace {

// The helper thread runs the second half of every job, the caller the first; each index once.
TEST(HelperThread, SplitsAJobIntoTwoHalvesAndPassesExceptionsOn) {
  detail::HelperThread helper;
  for (const std::size_t n : {0u, 1u, 2u, 7u, 160u}) {
    for (int round = 0; round < 50; ++round) {
      std::vector<int> visits(n, 0);
      helper.split(n, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) ++visits[i];
      });
      EXPECT_EQ(std::count(visits.begin(), visits.end(), 1), static_cast<std::ptrdiff_t>(n));
    }
  }
  const auto throw_in = [&](std::size_t half_start) {
    helper.split(10, [&](std::size_t begin, std::size_t) {
      if (begin == half_start) throw std::runtime_error("half " + std::to_string(begin));
    });
  };
  EXPECT_THROW(throw_in(5), std::runtime_error);  // the helper's half
  EXPECT_THROW(throw_in(0), std::runtime_error);  // the caller's half
  int after = 0;
  helper.split(4, [&](std::size_t begin, std::size_t end) {
    if (begin == 0) after += static_cast<int>(end);
  });
  EXPECT_EQ(after, 2) << "the helper still serves after an exception";
}

}  // namespace
}  // namespace sgdicp
