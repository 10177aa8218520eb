// A probe, never built by default: the drive part including identification code, which the
// dependency rule forbids. CTest host_sim_drive_cannot_include_identification builds it with the
// drive's include directories and passes only when the include is not found.
#include "dyncal_host/drive/simulated_drive.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
