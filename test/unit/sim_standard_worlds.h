// The simulator's standard worlds for the sim_* unit tests, generated once per (name, seed) and
// shared by the tests of one binary.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "ladar_perception/sim/world.h"

namespace ladar_perception {
namespace sim {

inline const World& cachedStandardWorld(const std::string& name, uint32_t seed) {
  static std::map<std::pair<std::string, uint32_t>, World> cache;
  auto it = cache.find({name, seed});
  if (it == cache.end()) {
    World w;
    std::string error;
    EXPECT_TRUE(makeStandardWorld(name, seed, &w, &error)) << error;
    it = cache.emplace(std::make_pair(name, seed), std::move(w)).first;
  }
  return it->second;
}

}  // namespace sim
}  // namespace ladar_perception
