# Both STM32G4 board images build warning-free, print their memory use and
# pass the static checks of the vector table, stack and ISR placement.
add_test(NAME target/stm32g4-boards COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/target/run_target_checks.sh)
set_tests_properties(target/stm32g4-boards PROPERTIES LABELS target TIMEOUT 900
  ENVIRONMENT "FD_TARGET_BUILD_DIR=${CMAKE_BINARY_DIR}/target")
