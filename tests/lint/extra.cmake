# Formatting and static analysis of all C sources.
add_test(NAME lint/clang-format
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/lint/check_format.sh ${PROJECT_SOURCE_DIR})
add_test(NAME lint/cppcheck
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/lint/check_cppcheck.sh ${PROJECT_SOURCE_DIR})
set_tests_properties(lint/clang-format lint/cppcheck PROPERTIES LABELS lint TIMEOUT 600)
