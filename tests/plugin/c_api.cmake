# The C ABI (plugin/include/gust/gust.h) compiled as C11 and run from C; included from
# tests/plugin/CMakeLists.txt. Like the GoogleTest suites it runs on the validated own device (lavapipe in CI)
# and fails on any validation error, which reaches it through the log hook.
add_executable(gust_c_api_test ${CMAKE_CURRENT_LIST_DIR}/test_c_api.c)
set_target_properties(gust_c_api_test PROPERTIES C_STANDARD 11 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
target_link_libraries(gust_c_api_test PRIVATE gust::gust)
gust_target_defaults(gust_c_api_test)
add_test(NAME c_api COMMAND gust_c_api_test)
set_tests_properties(c_api PROPERTIES TIMEOUT 600)
