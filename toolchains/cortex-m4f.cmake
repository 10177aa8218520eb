# Cortex-M4 with single-precision FPU (qemu board mps2-an386).
set(DYNCAL_FW_CPU_FLAGS -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard)
set(DYNCAL_FW_BOARD mps2-an386)
set(DYNCAL_FW_QEMU_CPU cortex-m4)
set(DYNCAL_FW_SCALAR float)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
