#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "support/test_scenes.h"
#include "viewcells/core/error.h"
#include "viewcells/core/isa.h"
#include "viewcells/core/binary_file.h"

namespace viewcells {
namespace {

constexpr char kMagic[5] = "TEST";

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void expect_rejected(const std::string& path, const std::string& fragment) {
  uint32_t version;
  try {
    read_container(path, kMagic, 1, version);
    FAIL() << "accepted " << fragment;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(BinaryFile, RoundTrip) {
  ByteWriter w;
  w.put<uint32_t>(7);
  w.put_array(std::vector<double>{1.5, -2.25, 1e300});
  w.put_string("hello");
  const std::string path = test::temp_path("roundtrip.bin");
  write_container(path, kMagic, 1, w.data());
  uint32_t version = 0;
  const std::string payload = read_container(path, kMagic, 1, version);
  EXPECT_EQ(version, 1u);
  ByteReader r(payload, path);
  EXPECT_EQ(r.get<uint32_t>(), 7u);
  EXPECT_EQ(r.get_array<double>(10), (std::vector<double>{1.5, -2.25, 1e300}));
  EXPECT_EQ(r.get_string(), "hello");
  EXPECT_TRUE(r.at_end());
  EXPECT_THROW(r.get<uint8_t>(), Error);
}

TEST(BinaryFile, HeaderBytesAreStable) {
  // Golden header: magic, version 1 (low 16 bits) and the Embree ISA code (third byte),
  // payload size 3, then checksum and compressed size.
  const std::string path = test::temp_path("golden.bin");
  write_container(path, kMagic, 1, "abc");
  const std::string file = read_all(path);
  ASSERT_GE(file.size(), 32u);
  EXPECT_EQ(file.substr(0, 4), "TEST");
  EXPECT_EQ(file.substr(4, 2), std::string("\x01\x00", 2));
  EXPECT_EQ(static_cast<uint8_t>(file[6]), embree_isa_code(embree_isa()));
  EXPECT_EQ(file[7], '\0');
  uint32_t version = 0;
  std::string isa;
  EXPECT_EQ(read_container(path, kMagic, 1, version, &isa), "abc");
  EXPECT_EQ(version, 1u);
  EXPECT_EQ(isa, embree_isa());
  EXPECT_EQ(file.substr(8, 8), std::string("\x03\x00\x00\x00\x00\x00\x00\x00", 8));
  uint64_t checksum;
  std::memcpy(&checksum, file.data() + 16, 8);
  EXPECT_EQ(checksum, fnv1a64("abc"));
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ULL);
}

TEST(BinaryFile, CorruptionIsRejected) {
  std::string payload(10000, '\0');
  for (size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<char>(i * 7919 % 251);
  const std::string good = test::temp_path("good.bin");
  write_container(good, kMagic, 1, payload);
  const std::string bytes = read_all(good);

  const std::string truncated = test::temp_path("truncated.bin");
  test::write_file(truncated, bytes.substr(0, bytes.size() - 10));
  expect_rejected(truncated, "truncated");

  const std::string header_only = test::temp_path("short.bin");
  test::write_file(header_only, bytes.substr(0, 12));
  expect_rejected(header_only, "too short");

  std::string flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x10;
  const std::string flipped_path = test::temp_path("flipped.bin");
  test::write_file(flipped_path, flipped);
  expect_rejected(flipped_path, "corrupt");

  std::string wrong_magic = bytes;
  wrong_magic[0] = 'X';
  const std::string magic_path = test::temp_path("magic.bin");
  test::write_file(magic_path, wrong_magic);
  expect_rejected(magic_path, "wrong magic");

  std::string newer = bytes;
  newer[4] = 9;
  const std::string newer_path = test::temp_path("newer.bin");
  test::write_file(newer_path, newer);
  expect_rejected(newer_path, "version 9");

  expect_rejected(test::temp_path("absent.bin"), "no such file");
  expect_rejected(std::filesystem::temp_directory_path().string(), "not a regular file");

  // A header claiming 2^50 payload bytes is refused before anything is allocated (here
  // because the zstd frame disagrees; a frame that agreed would meet the expansion bound).
  std::string huge = bytes;
  const uint64_t claim = uint64_t{1} << 50;
  std::memcpy(huge.data() + 8, &claim, 8);
  const std::string huge_path = test::temp_path("huge.bin");
  test::write_file(huge_path, huge);
  expect_rejected(huge_path, "corrupt");
}

TEST(BinaryFile, FailedWriteKeepsTheOldFile) {
  const std::string path = test::temp_path("keep.bin");
  write_container(path, kMagic, 1, "old");
  EXPECT_THROW(write_container(test::temp_path("no/such/dir/x.bin"), kMagic, 1, "new"), Error);
  uint32_t version;
  EXPECT_EQ(read_container(path, kMagic, 1, version), "old");
  // No temporary files are left behind.
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(path).parent_path()))
    files += entry.path().string().find(".tmp.") != std::string::npos;
  EXPECT_EQ(files, 0u);
}

}  // namespace
}  // namespace viewcells
