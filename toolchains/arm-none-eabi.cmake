# Bare-metal Arm (arm-none-eabi) compiler identity. Included by the per-CPU toolchain files.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
find_program(ARM_GCC arm-none-eabi-gcc)
find_program(ARM_GXX arm-none-eabi-g++)
if(NOT ARM_GCC OR NOT ARM_GXX)
  message(FATAL_ERROR "arm-none-eabi-gcc/g++ not found: run scripts/setup (installs gcc-arm-none-eabi, "
                      "libnewlib-arm-none-eabi, libstdc++-arm-none-eabi-dev, qemu-system-arm)")
endif()
set(CMAKE_C_COMPILER ${ARM_GCC})
set(CMAKE_CXX_COMPILER ${ARM_GXX})
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)  # no startup files during compiler checks
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE NEVER)  # Eigen's CMake package comes from the host

# Firmware tests run under qemu (the per-CPU file sets the board and CPU before including this one):
# CTest prefixes each image with this command. -icount shift=0: one guest instruction per virtual ns.
find_program(QEMU_SYSTEM_ARM qemu-system-arm)
if(NOT QEMU_SYSTEM_ARM)
  message(FATAL_ERROR "qemu-system-arm not found: run scripts/setup")
endif()
set(CMAKE_CROSSCOMPILING_EMULATOR ${QEMU_SYSTEM_ARM} -M ${DYNCAL_FW_BOARD} -cpu ${DYNCAL_FW_QEMU_CPU} -nographic
    -monitor none -serial none -icount shift=0 -semihosting-config enable=on,target=native -kernel)
