// The parameter store under torn writes (issue 23): kill -9 keeps the OS write cache, so
// FlashKill never tears a write. Here the store's only write path (write_file_atomically) is cut
// at every byte offset of the new table and at each step after it, as a power loss would; after
// each cut a drive starts on the same file with the old table or the new one, never a corrupt one.
// And if the active file itself were torn (a file system without atomic rename), the drive refuses
// it by its CRC and starts on the factory table, saying so.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "support/encoded_table.hpp"

namespace {

using namespace dyncal::host;

class StoreTornWrites : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("dyncal_torn_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "drive.table").string();
    JointArray fc_old{}, fc_new{}, beta{};
    for (int j = 0; j < robot_.num_joints; ++j) {
      fc_old[j] = 10.0 + j;
      fc_new[j] = 20.0 + j;
      beta[j] = 5.0;
    }
    old_ = dyncal::test::encoded_table(nominal_table("er20", fc_old, beta));
    new_ = dyncal::test::encoded_table(nominal_table("er20", fc_new, beta));
    ASSERT_NE(old_, new_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::vector<std::uint8_t> start_drive(std::string* note) const {
    SimulatedDrive d(robot_, scenario_, path_);
    *note = d.startup_note();
    return d.active_table_bytes();
  }
  RobotDescription robot_ = load_robot(default_robots_dir(), "er20");
  Scenario scenario_ = default_scenario(robot_);
  std::filesystem::path dir_;
  std::string path_;
  std::vector<std::uint8_t> old_, new_;
};

TEST_F(StoreTornWrites, EveryCutLeavesTheOldOrTheNewTable) {
  const long size = static_cast<long>(new_.size());
  long old_after = 0, new_after = 0;
  for (long cut = 0; cut <= size + 2; ++cut) {
    write_file_atomically(path_, old_);
    write_file_atomically(path_, new_, 0, cut);
    std::string note;
    const auto active = start_drive(&note);
    EXPECT_NE(note.find("table from"), std::string::npos) << "cut " << cut << ": " << note;
    if (active == old_) {
      ++old_after;
    } else {
      EXPECT_EQ(active, new_) << "cut " << cut << ": neither the old nor the new table";
      ++new_after;
    }
    // The next flash after a crash (a stale temporary file left behind) completes.
    write_file_atomically(path_, new_);
    EXPECT_EQ(start_drive(&note), new_) << "cut " << cut;
  }
  // Before the rename the old table survives; from the rename on, the new one.
  EXPECT_EQ(old_after, size + 2);
  EXPECT_EQ(new_after, 1);
}

TEST_F(StoreTornWrites, ATornActiveFileIsRefusedForTheFactoryTable) {
  SimulatedDrive factory(robot_, scenario_, (dir_ / "none.table").string());
  const auto factory_bytes = factory.active_table_bytes();
  for (size_t length = 0; length < new_.size(); ++length) {
    {
      std::ofstream out(path_, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(new_.data()), static_cast<std::streamsize>(length));
    }
    std::string note;
    EXPECT_EQ(start_drive(&note), factory_bytes) << "torn at " << length;
    EXPECT_NE(note.find("rejected"), std::string::npos) << "torn at " << length << ": " << note;
  }
}

}  // namespace
