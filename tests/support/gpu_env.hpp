// One validated Vulkan context per test binary; every test fails if the validation layer said anything.
#pragma once

#include <gtest/gtest.h>
#include <gust/gpu/context.hpp>

namespace gust::test {

/// The shared context (lavapipe in CI, validation always on). Created on first use.
gpu::Context& gpu_context();

/// Base fixture: records the validation count before the test and fails the test if it grew.
class GpuTest : public ::testing::Test {
  protected:
    void SetUp() override;
    void TearDown() override;
    gpu::Context& ctx() { return gpu_context(); }

  private:
    std::uint32_t messages_before_ = 0;
};

/// The same check for parameterized suites.
template <class Param>
class GpuTestWithParam : public GpuTest, public ::testing::WithParamInterface<Param> {};

} // namespace gust::test
