# Cortex-M7 with double-precision FPU (qemu board mps2-an500).
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
set(DYNCAL_FW_CPU_FLAGS -mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard)
set(DYNCAL_FW_BOARD mps2-an500)
set(DYNCAL_FW_QEMU_CPU cortex-m7)
set(DYNCAL_FW_SCALAR double)
find_program(QEMU_SYSTEM_ARM qemu-system-arm)
if(NOT QEMU_SYSTEM_ARM)
  message(FATAL_ERROR "qemu-system-arm not found: run scripts/setup")
endif()
# Firmware tests run under qemu: CTest prefixes the image with this command.
set(CMAKE_CROSSCOMPILING_EMULATOR ${QEMU_SYSTEM_ARM} -M ${DYNCAL_FW_BOARD} -cpu ${DYNCAL_FW_QEMU_CPU} -nographic
    -monitor none -serial none -icount shift=0 -semihosting-config enable=on,target=native -kernel)
