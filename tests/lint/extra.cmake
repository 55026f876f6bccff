# Formatting and static analysis of all C sources.
add_test(NAME lint/clang-format
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/lint/check_format.sh ${PROJECT_SOURCE_DIR})
add_test(NAME lint/cppcheck
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/lint/check_cppcheck.sh ${PROJECT_SOURCE_DIR})
set_tests_properties(lint/clang-format lint/cppcheck PROPERTIES LABELS lint TIMEOUT 600)
add_test(NAME lint/clang-tidy
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/lint/check_tidy.sh ${PROJECT_SOURCE_DIR} ${CMAKE_BINARY_DIR})
set_tests_properties(lint/clang-tidy PROPERTIES LABELS lint TIMEOUT 900)
