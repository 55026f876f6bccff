# Both STM32G4 board images build warning-free, print their memory use and
# pass the static checks of the vector table, stack and ISR placement.
add_test(NAME target/stm32g4-boards COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/target/run_target_checks.sh)
set_tests_properties(target/stm32g4-boards PROPERTIES LABELS target TIMEOUT 900
  ENVIRONMENT "FD_TARGET_BUILD_DIR=${CMAKE_BINARY_DIR}/target")

# The HAL's break / idle-state and comparator-trip register set-up
# (pwm_tim1.c, break_comp.c) on the host against fake register blocks, once
# per board header.
foreach(board b_g431b_esc1 g474)
  set(exe target_hal_regs_${board})
  add_executable(${exe} ${CMAKE_CURRENT_SOURCE_DIR}/target/hal_regs_test.c)
  string(TOUPPER ${board} board_uc)
  target_compile_definitions(${exe} PRIVATE FD_BOARD_${board_uc})
  target_include_directories(${exe} PRIVATE ${CMOCKA_INCLUDE} ${PROJECT_SOURCE_DIR}/hal
                             ${PROJECT_SOURCE_DIR}/hal/stm32g4)
  target_link_libraries(${exe} PRIVATE ${CMOCKA_LIB} m)
  fd_host_target(${exe})
  add_test(NAME target/hal_regs_${board} COMMAND ${exe})
  set_tests_properties(target/hal_regs_${board} PROPERTIES LABELS target TIMEOUT 60)
endforeach()

# The PWM-period interrupt (adc.c): JEOS of every ADC in use armed, the
# registered period body run once per period at the last end, no wait;
# on the host against fake register blocks, once per board header.
foreach(board b_g431b_esc1 g474)
  set(exe target_hal_adc_${board})
  add_executable(${exe} ${CMAKE_CURRENT_SOURCE_DIR}/target/hal_adc_test.c)
  string(TOUPPER ${board} board_uc)
  target_compile_definitions(${exe} PRIVATE FD_BOARD_${board_uc})
  target_include_directories(${exe} PRIVATE ${CMOCKA_INCLUDE} ${PROJECT_SOURCE_DIR}/hal
                             ${PROJECT_SOURCE_DIR}/hal/stm32g4)
  target_link_libraries(${exe} PRIVATE ${CMOCKA_LIB} m)
  fd_host_target(${exe})
  add_test(NAME target/hal_adc_${board} COMMAND ${exe})
  set_tests_properties(target/hal_adc_${board} PROPERTIES LABELS target TIMEOUT 60)
endforeach()
