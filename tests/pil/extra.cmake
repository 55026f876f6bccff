# PIL on QEMU mps2-an386 (docs/pil.md): the Cortex-M4F image replays the
# ISR inputs of SIL runs of this build; outputs compared, instructions
# counted (report in the test output and in <build>/pil/benchmarks.md).
set(FD_PIL_PYTHON "${FD_PYTHON}")
if(NOT FD_PIL_PYTHON AND EXISTS ${PROJECT_SOURCE_DIR}/.venv/bin/python)
  set(FD_PIL_PYTHON ${PROJECT_SOURCE_DIR}/.venv/bin/python)
endif()
find_program(FD_QEMU_ARM qemu-system-arm)
find_program(FD_ARM_GCC arm-none-eabi-gcc)
if(FD_PIL_PYTHON AND FD_QEMU_ARM AND FD_ARM_GCC)
  add_test(NAME pil/qemu-mps2-an386
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/pil/run_pil.sh ${PROJECT_SOURCE_DIR}
                   ${CMAKE_BINARY_DIR}/pil ${FD_PIL_PYTHON} $<TARGET_FILE:fluxdrive-sil>)
  set_tests_properties(pil/qemu-mps2-an386 PROPERTIES LABELS pil TIMEOUT 900)
else()
  message(STATUS "pil/qemu-mps2-an386 not registered: needs the tools venv (FD_PYTHON), "
                 "qemu-system-arm and arm-none-eabi-gcc")
endif()
