# Warning and code-generation flags shared by all fluxdrive targets.
set(FD_WARNINGS -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes
    -Wmissing-prototypes -Wconversion -Wno-sign-conversion)

# The MCU core and app: single precision only (ARCHITECTURE.md, "Conventions").
# -fno-math-errno: the core never reads errno, so sqrtf is the VSQRT.F32
# instruction (x86: SQRTSS) instead of a libm call that sets errno for a
# negative argument; results are IEEE-754 identical.
set(FD_CORE_FLAGS ${FD_WARNINGS} -Wdouble-promotion -fsingle-precision-constant
    -Wfloat-equal -Wvla -fno-math-errno)

option(FD_SANITIZE "Build with address and undefined-behaviour sanitizers" OFF)
if(FD_SANITIZE AND NOT CMAKE_CROSSCOMPILING)
  # -O1 in the Debug build (host-debug, the test build): the sanitizers'
  # own advice for speed; -O0 made the Eigen reference checks 15x slower
  # (core/ref_kf_mech 43 s -> 2.9 s of CPU) and the SIL runner 2x slower,
  # for the same results (summaries identical but the wall time).
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer $<$<CONFIG:Debug>:-O1>)
  add_link_options(-fsanitize=address,undefined)
endif()

function(fd_core_target tgt)
  target_compile_options(${tgt} PRIVATE ${FD_CORE_FLAGS})
endfunction()

function(fd_host_target tgt)
  target_compile_options(${tgt} PRIVATE ${FD_WARNINGS})
endfunction()
