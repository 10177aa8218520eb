// The MPS2 `.param_store` region as a FlashDevice: on qemu it is RAM (the SSRAM standing in for
// flash), so erase and program are emulated with flash semantics — erase sets a 1 KiB sector to
// 0xFF, programming can only clear bits — so that code relying on more than that fails here too.
#include <cstdint>

#include "dyncal_cortex_m/flash_parameter_store.hpp"

extern "C" std::uint8_t __param_store_start[];
extern "C" std::uint8_t __param_store_end[];

namespace dyncal::cortex_m {
namespace {

class Mps2ParamFlash final : public FlashDevice {
 public:
  int size() const noexcept override { return static_cast<int>(__param_store_end - __param_store_start); }
  int sector_size() const noexcept override { return 1024; }
  bool erase(int offset) noexcept override {
    if (offset < 0 || offset % sector_size() != 0 || offset + sector_size() > size()) return false;
    volatile std::uint8_t* p = __param_store_start + offset;
    for (int i = 0; i < sector_size(); ++i) p[i] = 0xFF;
    return true;
  }
  bool program(int offset, const std::uint8_t* bytes, int count) noexcept override {
    if (offset < 0 || count < 0 || offset + count > size()) return false;
    volatile std::uint8_t* p = __param_store_start + offset;
    bool same = true;
    for (int i = 0; i < count; ++i) {
      p[i] = static_cast<std::uint8_t>(p[i] & bytes[i]);  // flash can only clear bits
      same = same && p[i] == bytes[i];
    }
    return same;
  }
  const std::uint8_t* data() const noexcept override { return __param_store_start; }
};

}  // namespace

FlashDevice& mps2_param_flash() noexcept {
  static Mps2ParamFlash flash;
  return flash;
}

}  // namespace dyncal::cortex_m
