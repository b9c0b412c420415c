#include "gpu_env.hpp"

#include <cstdlib>
#include <iostream>
#include <memory>

namespace gust::test {

gpu::Context& gpu_context() {
    static std::unique_ptr<gpu::Context> context = [] {
        gpu::ContextDesc desc;
        desc.validation = true;
        desc.on_message = [](gpu::Severity severity, const std::string& message) {
            if (severity != gpu::Severity::Info) std::cerr << "[vulkan] " << message << "\n";
        };
        auto ctx = gpu::Context::create(desc);
        if (!ctx) {
            std::cerr << "cannot create a Vulkan context: " << ctx.message() << "\n";
            std::abort();
        }
        return std::move(ctx.value());
    }();
    return *context;
}

void GpuTest::SetUp() {
    messages_before_ = gpu_context().validation_messages();
}

void GpuTest::TearDown() {
    EXPECT_EQ(gpu_context().validation_messages(), messages_before_)
        << "validation layer: " << gpu_context().last_validation_message();
}

} // namespace gust::test
