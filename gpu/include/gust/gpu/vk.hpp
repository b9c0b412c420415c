// Vulkan without global symbols: every entry point is called through a per-context dispatch table, so
// gust can live inside a host engine that loads Vulkan its own way (Jolt-style tiered backends).
#pragma once

#ifndef VK_NO_PROTOTYPES
#define VK_NO_PROTOTYPES
#endif
#include <vulkan/vulkan.h>

namespace gust::gpu {

// Entry points loaded from vkGetInstanceProcAddr(VK_NULL_HANDLE, ...).
#define GUST_VK_GLOBAL_FUNCTIONS(X)                                                                          \
    X(vkCreateInstance)                                                                                      \
    X(vkEnumerateInstanceLayerProperties)                                                                    \
    X(vkEnumerateInstanceExtensionProperties)                                                                \
    X(vkEnumerateInstanceVersion)

// Entry points loaded from vkGetInstanceProcAddr(instance, ...).
#define GUST_VK_INSTANCE_FUNCTIONS(X)                                                                        \
    X(vkDestroyInstance)                                                                                     \
    X(vkEnumeratePhysicalDevices)                                                                            \
    X(vkGetPhysicalDeviceProperties)                                                                         \
    X(vkGetPhysicalDeviceProperties2)                                                                        \
    X(vkGetPhysicalDeviceImageFormatProperties2)                                                             \
    X(vkGetPhysicalDeviceFeatures2)                                                                          \
    X(vkGetPhysicalDeviceQueueFamilyProperties)                                                              \
    X(vkGetPhysicalDeviceMemoryProperties)                                                                   \
    X(vkEnumerateDeviceExtensionProperties)                                                                  \
    X(vkCreateDevice)                                                                                        \
    X(vkGetDeviceProcAddr)

// Optional instance entry points (VK_EXT_debug_utils); null when the extension is off.
#define GUST_VK_DEBUG_FUNCTIONS(X)                                                                           \
    X(vkCreateDebugUtilsMessengerEXT)                                                                        \
    X(vkDestroyDebugUtilsMessengerEXT)                                                                       \
    X(vkSetDebugUtilsObjectNameEXT)                                                                          \
    X(vkCmdBeginDebugUtilsLabelEXT)                                                                          \
    X(vkCmdEndDebugUtilsLabelEXT)

// Optional device entry points (VK_KHR_external_memory_fd, ContextDesc::external_memory); null when off.
#define GUST_VK_EXTERNAL_MEMORY_FUNCTIONS(X) X(vkGetMemoryFdKHR)

// Entry points loaded from vkGetDeviceProcAddr(device, ...).
#define GUST_VK_DEVICE_FUNCTIONS(X)                                                                          \
    X(vkDestroyDevice)                                                                                       \
    X(vkCreatePipelineCache)                                                                                 \
    X(vkDestroyPipelineCache)                                                                                \
    X(vkGetPipelineCacheData)                                                                                \
    X(vkGetDeviceQueue)                                                                                      \
    X(vkDeviceWaitIdle)                                                                                      \
    X(vkQueueWaitIdle)                                                                                       \
    X(vkCreateBuffer)                                                                                        \
    X(vkDestroyBuffer)                                                                                       \
    X(vkGetBufferMemoryRequirements)                                                                         \
    X(vkBindBufferMemory)                                                                                    \
    X(vkGetBufferDeviceAddress)                                                                              \
    X(vkAllocateMemory)                                                                                      \
    X(vkFreeMemory)                                                                                          \
    X(vkMapMemory)                                                                                           \
    X(vkUnmapMemory)                                                                                         \
    X(vkCreateImage)                                                                                         \
    X(vkDestroyImage)                                                                                        \
    X(vkGetImageMemoryRequirements)                                                                          \
    X(vkBindImageMemory)                                                                                     \
    X(vkCreateImageView)                                                                                     \
    X(vkDestroyImageView)                                                                                    \
    X(vkCreateSampler)                                                                                       \
    X(vkDestroySampler)                                                                                      \
    X(vkCmdCopyBufferToImage)                                                                                \
    X(vkCmdCopyImageToBuffer)                                                                                \
    X(vkCreateShaderModule)                                                                                  \
    X(vkDestroyShaderModule)                                                                                 \
    X(vkCreatePipelineLayout)                                                                                \
    X(vkDestroyPipelineLayout)                                                                               \
    X(vkCreateComputePipelines)                                                                              \
    X(vkCreateGraphicsPipelines)                                                                             \
    X(vkDestroyPipeline)                                                                                     \
    X(vkCreateCommandPool)                                                                                   \
    X(vkDestroyCommandPool)                                                                                  \
    X(vkAllocateCommandBuffers)                                                                              \
    X(vkFreeCommandBuffers)                                                                                  \
    X(vkBeginCommandBuffer)                                                                                  \
    X(vkEndCommandBuffer)                                                                                    \
    X(vkCreateFence)                                                                                         \
    X(vkDestroyFence)                                                                                        \
    X(vkResetFences)                                                                                         \
    X(vkWaitForFences)                                                                                       \
    X(vkQueueSubmit)                                                                                         \
    X(vkCreateQueryPool)                                                                                     \
    X(vkDestroyQueryPool)                                                                                    \
    X(vkGetQueryPoolResults)                                                                                 \
    X(vkCmdResetQueryPool)                                                                                   \
    X(vkCmdWriteTimestamp)                                                                                   \
    X(vkCmdBindPipeline)                                                                                     \
    X(vkCmdPushConstants)                                                                                    \
    X(vkCmdDispatch)                                                                                         \
    X(vkCmdDispatchIndirect)                                                                                 \
    X(vkCmdPipelineBarrier)                                                                                  \
    X(vkCmdFillBuffer)                                                                                       \
    X(vkCmdCopyBuffer)                                                                                       \
    X(vkCmdUpdateBuffer)                                                                                     \
    X(vkCreateRenderPass)                                                                                    \
    X(vkDestroyRenderPass)                                                                                   \
    X(vkCreateFramebuffer)                                                                                   \
    X(vkDestroyFramebuffer)                                                                                  \
    X(vkCmdBeginRenderPass)                                                                                  \
    X(vkCmdEndRenderPass)                                                                                    \
    X(vkCmdSetViewport)                                                                                      \
    X(vkCmdSetScissor)                                                                                       \
    X(vkCmdDraw)

#define GUST_VK_DECLARE(name) PFN_##name name = nullptr;

/// Function pointers for one instance and device. Owned by gpu::Context; read-only after creation.
struct Dispatch {
    PFN_vkGetInstanceProcAddr vkGetInstanceProcAddr = nullptr;
    GUST_VK_GLOBAL_FUNCTIONS(GUST_VK_DECLARE)
    GUST_VK_INSTANCE_FUNCTIONS(GUST_VK_DECLARE)
    GUST_VK_DEBUG_FUNCTIONS(GUST_VK_DECLARE)
    GUST_VK_DEVICE_FUNCTIONS(GUST_VK_DECLARE)
    GUST_VK_EXTERNAL_MEMORY_FUNCTIONS(GUST_VK_DECLARE)
};

#undef GUST_VK_DECLARE

/// "VK_ERROR_OUT_OF_DEVICE_MEMORY" etc., for messages.
const char* to_string(VkResult result);

} // namespace gust::gpu
