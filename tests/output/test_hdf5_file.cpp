// HDF5 results files: every kind of dataset and attribute round-trips through a
// closed and reopened file, appendable tables grow across reopenings, and every
// failure is an Hdf5Error naming the file and the object, with nothing printed by HDF5.
#include "fem/hdf5_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace {

namespace fs = std::filesystem;
using rsw::fem::Hdf5Error;
using rsw::fem::Hdf5Mode;
using rsw::fem::RowMajorMatrix;
using File = rsw::fem::Hdf5File;

// The fixture takes the wrapper's name so that tests read Hdf5File.<Behaviour>.
class Hdf5File : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rsw_h5_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    path_ = dir_ / "results.h5";
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
  fs::path path_;
};

// Runs `action`, expects an Hdf5Error, and returns its message.
template <typename Action>
std::string hdf5_error_of(Action action) {
  try {
    action();
  } catch (const Hdf5Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an Hdf5Error";
  return {};
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST_F(Hdf5File, DatasetsRoundTripThroughReopenedFile) {
  const std::vector<double> t = {0.0, 1e-3 / 3, 2e-3, -4.5e300};
  const std::vector<int> flags = {0, 1, -7, 2147483647};
  {
    File file(path_, Hdf5Mode::truncate);
    file.write("/signals/t", t);  // creates /signals
    file.write("/signals/flags", flags);
    file.write("/empty", std::vector<double>{});
  }
  File file(path_, Hdf5Mode::read);
  EXPECT_EQ(file.read_doubles("/signals/t"), t);
  EXPECT_EQ(file.read_ints("/signals/flags"), flags);
  EXPECT_TRUE(file.read_doubles("/empty").empty());
  EXPECT_EQ(file.shape("/signals/t"), (std::vector<std::size_t>{4}));
}

TEST_F(Hdf5File, ScalarIsWrittenWithAScalarDataspaceAndReadBack) {
  {
    rsw::fem::Hdf5File file(path_, rsw::fem::Hdf5Mode::truncate);
    file.write_scalar("/energy/stored", 1234.5);
  }
  rsw::fem::Hdf5File file(path_, rsw::fem::Hdf5Mode::read);
  EXPECT_EQ(file.read_scalar("/energy/stored"), 1234.5);
  EXPECT_EQ(file.shape("/energy/stored"), std::vector<std::size_t>{});
  EXPECT_THROW(file.read_doubles("/energy/stored"), std::runtime_error);  // not a 1-D dataset
}

TEST_F(Hdf5File, MatrixRoundTripsRowMajor) {
  RowMajorMatrix m{2, 3, {1, 2, 3, 4, 5, 6}};
  {
    File file(path_, Hdf5Mode::truncate);
    file.write("/nugget/profile", m);
  }
  File file(path_, Hdf5Mode::read);
  const RowMajorMatrix back = file.read_matrix("/nugget/profile");
  EXPECT_EQ(back.n_rows, 2u);
  EXPECT_EQ(back.n_cols, 3u);
  EXPECT_EQ(back.values, m.values);
  EXPECT_EQ(back(1, 0), 4.0);
  EXPECT_EQ(file.shape("/nugget/profile"), (std::vector<std::size_t>{2, 3}));
}

TEST_F(Hdf5File, StringDatasetAndAttributesRoundTrip) {
  const std::string yaml = "weld:\n  current: 8 kA  # peak\n  name: \"Düsseldorf\"\n";
  {
    File file(path_, Hdf5Mode::truncate);
    file.write_string("/config", yaml);
    file.create_group("/nugget");
    file.set_attribute("/", "version", "0.1.0");
    file.set_attribute("/", "wall_time", 12.5);
    file.set_attribute("/config", "format", "yaml");
    file.set_attribute("/nugget", "unit", "m");
    file.set_attribute("/nugget", "unit", "mm");  // replaces
  }
  File file(path_, Hdf5Mode::read);
  EXPECT_EQ(file.read_string("/config"), yaml);
  EXPECT_EQ(file.string_attribute("/", "version"), "0.1.0");
  EXPECT_EQ(file.double_attribute("/", "wall_time"), 12.5);
  EXPECT_EQ(file.string_attribute("/config", "format"), "yaml");
  EXPECT_EQ(file.string_attribute("/nugget", "unit"), "mm");
  EXPECT_TRUE(file.has_attribute("/", "version"));
  EXPECT_FALSE(file.has_attribute("/", "author"));
  EXPECT_EQ(file.attribute_names("/"), (std::vector<std::string>{"version", "wall_time"}));
}

TEST_F(Hdf5File, AppendedRowsReadBackInOrder) {
  {
    File file(path_, Hdf5Mode::truncate);
    file.create_appendable("/study/results", 3, 2);  // chunks smaller than the table
    file.create_appendable("/study/run_time");
    for (int run = 0; run < 5; ++run) {
      file.append("/study/results", {double(run), 10.0 * run, -1.0 * run});
      file.append("/study/run_time", {0.5 * run});
    }
  }
  File file(path_, Hdf5Mode::read);
  const RowMajorMatrix results = file.read_matrix("/study/results");
  ASSERT_EQ(results.n_rows, 5u);
  ASSERT_EQ(results.n_cols, 3u);
  for (std::size_t run = 0; run < 5; ++run) {
    EXPECT_EQ(results(run, 0), double(run));
    EXPECT_EQ(results(run, 1), 10.0 * run);
    EXPECT_EQ(results(run, 2), -1.0 * run);
  }
  EXPECT_EQ(file.read_doubles("/study/run_time"), (std::vector<double>{0, 0.5, 1, 1.5, 2}));
}

TEST_F(Hdf5File, AppendModeResumesAnExistingTable) {
  {
    File file(path_, Hdf5Mode::append);  // creates the file
    file.create_appendable("/study/results", 2);
    file.append("/study/results", {1, 2});
  }
  {
    File file(path_, Hdf5Mode::append);  // keeps what is there
    ASSERT_TRUE(file.exists("/study/results"));
    EXPECT_THROW(file.create_appendable("/study/results", 2), Hdf5Error);
    file.append("/study/results", {3, 4});
  }
  File file(path_, Hdf5Mode::read);
  EXPECT_EQ(file.read_matrix("/study/results").values, (std::vector<double>{1, 2, 3, 4}));
}

TEST_F(Hdf5File, AppendedRowIsOnDiskBeforeClose) {
  File writer(path_, Hdf5Mode::truncate);
  writer.create_appendable("/rows", 2);
  writer.append("/rows", {7, 8});
  // A copy of the file as a killed process would leave it already holds the row.
  const fs::path copy = dir_ / "copy.h5";
  fs::copy_file(path_, copy);
  File reader(copy, Hdf5Mode::read);
  EXPECT_EQ(reader.read_matrix("/rows").values, (std::vector<double>{7, 8}));
}

TEST_F(Hdf5File, AppendingRowOfWrongLengthNamesPath) {
  File file(path_, Hdf5Mode::truncate);
  file.create_appendable("/study/results", 3);
  const std::string msg = hdf5_error_of([&] { file.append("/study/results", {1, 2}); });
  EXPECT_TRUE(contains(msg, "/study/results")) << msg;
  EXPECT_TRUE(contains(msg, "3 columns")) << msg;
  file.write("/fixed", std::vector<double>{1});
  EXPECT_THROW(file.append("/fixed", {2}), Hdf5Error);
}

TEST_F(Hdf5File, MissingDatasetErrorNamesPath) {
  {
    File file(path_, Hdf5Mode::truncate);
    file.write("/signals/t", std::vector<double>{0});
  }
  File file(path_, Hdf5Mode::read);
  ::testing::internal::CaptureStderr();
  const std::string msg = hdf5_error_of([&] { file.read_doubles("/signals/missing"); });
  const std::string printed = ::testing::internal::GetCapturedStderr();
  EXPECT_TRUE(contains(msg, path_.string())) << msg;
  EXPECT_TRUE(contains(msg, "/signals/missing")) << msg;
  EXPECT_EQ(printed, "") << "HDF5 printed its error stack";
}

TEST_F(Hdf5File, MissingFileErrorNamesFile) {
  const std::string msg = hdf5_error_of([&] { File(dir_ / "absent.h5", Hdf5Mode::read); });
  EXPECT_TRUE(contains(msg, (dir_ / "absent.h5").string())) << msg;
}

TEST_F(Hdf5File, WrongRankAndMissingAttributeErrorsNameObject) {
  File file(path_, Hdf5Mode::truncate);
  file.write("/signals/t", std::vector<double>{0, 1});
  std::string msg = hdf5_error_of([&] { file.read_matrix("/signals/t"); });
  EXPECT_TRUE(contains(msg, "/signals/t")) << msg;
  msg = hdf5_error_of([&] { file.string_attribute("/signals", "unit"); });
  EXPECT_TRUE(contains(msg, "/signals@unit")) << msg;
  msg = hdf5_error_of([&] { file.set_attribute("/nowhere", "unit", "m"); });
  EXPECT_TRUE(contains(msg, "/nowhere")) << msg;
}

TEST_F(Hdf5File, ExistsAndListFollowTheGroupTree) {
  File file(path_, Hdf5Mode::truncate);
  file.write("/signals/t", std::vector<double>{0});
  file.write("/signals/I", std::vector<double>{8e3});
  file.create_group("/nugget/liquidus");
  EXPECT_TRUE(file.exists("/"));
  EXPECT_TRUE(file.exists("/signals"));
  EXPECT_TRUE(file.exists("/signals/t"));
  EXPECT_TRUE(file.exists("/nugget/liquidus"));
  EXPECT_FALSE(file.exists("/features"));
  EXPECT_FALSE(file.exists("/signals/t/below_a_dataset"));
  EXPECT_FALSE(file.exists("/features/width"));
  EXPECT_EQ(file.list("/"), (std::vector<std::string>{"nugget", "signals"}));
  EXPECT_EQ(file.list("/signals"), (std::vector<std::string>{"I", "t"}));
  EXPECT_THROW(file.list("/signals/t"), Hdf5Error);
}

TEST_F(Hdf5File, WriteReplacesExistingDatasetButNotGroup) {
  File file(path_, Hdf5Mode::truncate);
  file.write("/signals/t", std::vector<double>{0, 1, 2});
  file.write("/signals/t", std::vector<double>{5});
  EXPECT_EQ(file.read_doubles("/signals/t"), (std::vector<double>{5}));
  const std::string msg = hdf5_error_of([&] { file.write("/signals", std::vector<double>{1}); });
  EXPECT_TRUE(contains(msg, "not a dataset")) << msg;
  EXPECT_TRUE(file.exists("/signals/t"));
}

TEST_F(Hdf5File, ReadOnlyFileRefusesWrites) {
  { File file(path_, Hdf5Mode::truncate); }
  File file(path_, Hdf5Mode::read);
  const std::string msg = hdf5_error_of([&] { file.write("/x", std::vector<double>{1}); });
  EXPECT_TRUE(contains(msg, "read-only")) << msg;
  EXPECT_THROW(file.set_attribute("/", "version", "1"), Hdf5Error);
}

TEST_F(Hdf5File, MovedFileStaysUsableAndClosedFileRefusesUse) {
  File first(path_, Hdf5Mode::truncate);
  File second = std::move(first);
  second.write("/x", std::vector<int>{1});
  second.close();
  EXPECT_THROW(second.read_ints("/x"), Hdf5Error);
  File reopened(path_, Hdf5Mode::read);
  EXPECT_EQ(reopened.read_ints("/x"), (std::vector<int>{1}));
}

}  // namespace
