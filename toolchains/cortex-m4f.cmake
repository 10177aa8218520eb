# Cortex-M4 with single-precision FPU (qemu board mps2-an386).
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
set(DYNCAL_FW_CPU_FLAGS -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard)
set(DYNCAL_FW_BOARD mps2-an386)
set(DYNCAL_FW_QEMU_CPU cortex-m4)
set(DYNCAL_FW_SCALAR float)
find_program(QEMU_SYSTEM_ARM qemu-system-arm)
if(NOT QEMU_SYSTEM_ARM)
  message(FATAL_ERROR "qemu-system-arm not found: run scripts/setup")
endif()
# Firmware tests run under qemu: CTest prefixes the image with this command.
set(CMAKE_CROSSCOMPILING_EMULATOR ${QEMU_SYSTEM_ARM} -M ${DYNCAL_FW_BOARD} -cpu ${DYNCAL_FW_QEMU_CPU} -nographic
    -monitor none -serial none -icount shift=0 -semihosting-config enable=on,target=native -kernel)
