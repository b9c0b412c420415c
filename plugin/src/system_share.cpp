// SystemDesc::exported_copies: each cascade's wind texture copied into images whose memory another VkDevice
// on the same physical device imports (a host engine's), so gust never submits on the host's queue and the
// wind still reaches the host's shaders without a copy through the CPU (docs/api.md "Sharing the wind image
// with another device").
#include "system_impl.hpp"

namespace gust {

using namespace detail;

Outcome create_exported(System::Impl& m, std::uint32_t copies) {
    m.exported_copies = copies;
    for (const WindTexture& t : m.frame->textures()) {
        for (std::uint32_t s = 0; s < copies; ++s) {
            gpu::ImageDesc desc;
            desc.extent = {t.extent[0], t.extent[1], t.extent[2]};
            desc.format = t.format;
            // What the host samples and may copy (its engine's texture of it), what gust copies into.
            desc.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                         VK_IMAGE_USAGE_TRANSFER_DST_BIT;
            desc.volume = true;
            desc.exportable = true;
            desc.name = "gust exported wind";
            auto image = gpu::Image::create(*m.ctx, desc);
            if (!image) return device_failure(image.status());
            m.exported.push_back(std::move(*image));
        }
    }
    return {};
}

Outcome System::export_wind_copy(std::uint32_t cascade, std::uint32_t slot, ExportedImage& out) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("export_wind_copy");
    Impl& m = *impl_;
    if (m.exported_copies == 0)
        return Outcome(ErrorCode::NotEnabled,
                       "export_wind_copy: the System was created with exported_copies 0");
    const std::size_t cascades = m.frame->textures().size();
    if (cascade >= cascades || slot >= m.exported_copies)
        return invalid("export_wind_copy: cascade " + std::to_string(cascade) + ", copy " +
                       std::to_string(slot) + " of " + std::to_string(cascades) + " cascades and " +
                       std::to_string(m.exported_copies) + " copies");
    const gpu::Image& image = m.exported[cascade * m.exported_copies + slot];
    auto fd = image.export_fd();
    if (!fd) return device_failure(fd.status());
    out.fd = *fd;
    out.allocation_size = image.allocation_size();
    out.memory_type_index = image.memory_type();
    out.format = image.format();
    out.extent[0] = image.extent().width;
    out.extent[1] = image.extent().height;
    out.extent[2] = image.extent().depth;
    out.usage = image.usage();
    return {};
}

Outcome System::copy_wind_textures(std::uint32_t slot) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("copy_wind_textures");
    Impl& m = *impl_;
    if (m.exported_copies == 0)
        return Outcome(ErrorCode::NotEnabled,
                       "copy_wind_textures: the System was created with exported_copies 0");
    if (slot >= m.exported_copies)
        return invalid("copy_wind_textures: copy " + std::to_string(slot) + " of " +
                       std::to_string(m.exported_copies));
    if (Outcome o = m.refuse_after_failure(); !o) return o;
    return guarded([&]() -> Outcome {
        const Status done = m.ctx->submit_and_wait([&](VkCommandBuffer cmd) {
            // The texels are what the cascade's last step copied into its texture: the same bytes, read
            // without moving the texture out of the layout the host may be sampling it in.
            gpu::barrier(*m.ctx, cmd);
            for (std::size_t k = 0; k < m.frame->textures().size(); ++k) {
                gpu::Image& copy = m.exported[k * m.exported_copies + slot];
                // The host is done with the old contents (the call's contract), so no ownership is acquired
                // back from VK_QUEUE_FAMILY_EXTERNAL: a transition from UNDEFINED needs none.
                copy.discard();
                copy.transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
                copy.copy_from(cmd, m.frame->texels(k));
                copy.release_to_external(cmd, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
            }
        });
        if (!done) return m.remember(device_failure(done));
        return {};
    });
}

} // namespace gust
