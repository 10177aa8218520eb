# Cortex-M7 with double-precision FPU (qemu board mps2-an500).
set(DYNCAL_FW_CPU_FLAGS -mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard)
set(DYNCAL_FW_BOARD mps2-an500)
set(DYNCAL_FW_QEMU_CPU cortex-m7)
set(DYNCAL_FW_SCALAR double)
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
