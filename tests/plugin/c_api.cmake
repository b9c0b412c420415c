# The C ABI (plugin/include/gust/gust.h) compiled as C11 and run from C; included from
# tests/plugin/CMakeLists.txt. Like the GoogleTest suites it runs with the validation layer on (lavapipe in
# CI) and fails on any validation message: gust's through the log hook, the host's through its messenger.
add_executable(gust_c_api_test ${CMAKE_CURRENT_LIST_DIR}/test_c_api.c)
set_target_properties(gust_c_api_test PROPERTIES C_STANDARD 11 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
# libdl: the host-device test loads Vulkan itself, as an engine would.
target_link_libraries(gust_c_api_test PRIVATE gust::gust ${CMAKE_DL_LIBS})
gust_target_defaults(gust_c_api_test)
# Which outcome gust_system_export_vdb must have.
target_compile_definitions(gust_c_api_test PRIVATE GUST_WITH_OPENVDB=$<BOOL:${GUST_WITH_OPENVDB}>)
add_test(NAME c_api COMMAND gust_c_api_test)
set_tests_properties(c_api PROPERTIES TIMEOUT 600)
