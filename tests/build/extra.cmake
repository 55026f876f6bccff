# The core and app cross-compile for Cortex-M4F with -Werror; sizes printed.
add_test(NAME build/cortex-m4f
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/build/cross_build.sh ${PROJECT_SOURCE_DIR}
                 ${CMAKE_BINARY_DIR}/cross-m4f)
set_tests_properties(build/cortex-m4f PROPERTIES LABELS build TIMEOUT 600)
