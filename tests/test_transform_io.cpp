// Tests of rigid transforms as text (transform_io.hpp).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <string_view>

#include <unistd.h>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/io/transform_io.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::test::random_rigid;
using sgdicp::test::TempDir;

namespace fs = std::filesystem;

// Row-major numbers with 17 significant digits, `count` of them (12 or 16), joined by `sep`.
std::string numbers(const Eigen::Matrix4d& t, int count, const std::string& sep) {
  std::ostringstream s;
  s.precision(17);
  for (int i = 0; i < count; ++i) {
    if (i > 0) s << sep;
    s << t(i / 4, i % 4);
  }
  return s.str();
}

double max_abs_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

// Expects parse_transform(text, what) to throw FormatError whose message names `what`.
void expect_format_error(const std::string& text, const std::string& what,
                         const std::string& also = "") {
  try {
    (void)sgdicp::parse_transform(text, what);
    ADD_FAILURE() << "no error for: " << text;
  } catch (const sgdicp::FormatError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(what), std::string::npos) << message;
    if (!also.empty()) {
      EXPECT_NE(message.find(also), std::string::npos) << message;
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type for '" << text << "': " << e.what();
  }
}

TEST(ParseTransform, TwelveAndSixteenNumbers) {
  std::mt19937_64 rng(41);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Matrix4d t = random_rigid(rng, 100.0);
    const Eigen::Matrix4d a = sgdicp::parse_transform(numbers(t, 12, " "), "twelve");
    const Eigen::Matrix4d b = sgdicp::parse_transform(numbers(t, 16, " "), "sixteen");
    ASSERT_LT(max_abs_diff(a, t), 1e-14);
    ASSERT_LT(max_abs_diff(b, t), 1e-14);
    ASSERT_EQ(a.row(3), Eigen::RowVector4d(0, 0, 0, 1));
    ASSERT_TRUE(sgdicp::is_rigid_transform(a, 1e-14));
  }
  // Exact values for a simple one: a 90 degree yaw and a translation.
  const Eigen::Matrix4d t = sgdicp::parse_transform("0 -1 0 1\n1 0 0 2\n0 0 1 3\n", "simple");
  Eigen::Matrix4d expected;
  expected << 0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1;
  EXPECT_LT(max_abs_diff(t, expected), 1e-15);
  EXPECT_EQ((t.topRightCorner<3, 1>()), Eigen::Vector3d(1, 2, 3));
}

TEST(ParseTransform, SeparatorsCommentsAndBrackets) {
  std::mt19937_64 rng(42);
  const Eigen::Matrix4d t = random_rigid(rng, 100.0);
  const std::string ws = numbers(t, 16, " ");
  const std::string variants[] = {
      numbers(t, 16, ","),
      numbers(t, 16, ", "),
      numbers(t, 12, " ,\t"),
      numbers(t, 16, "\n"),
      numbers(t, 16, "\r\n") + "\r\n",
      numbers(t, 12, ";"),
      "# a comment line\n" + ws + "\n# trailing comment\n",
      "\n\n   " + ws + "   \n\n",
      ws + " # comment after the numbers 1 2 3",
      "[" + numbers(t, 16, ", ") + "]",
  };
  for (const std::string& text : variants) {
    SCOPED_TRACE(text);
    const Eigen::Matrix4d parsed = sgdicp::parse_transform(text, "variant");
    EXPECT_LT(max_abs_diff(parsed, t), 1e-14);
  }
  // Full numpy print of a 4x4.
  std::ostringstream numpy;
  numpy.precision(17);
  numpy << "[";
  for (int r = 0; r < 4; ++r) {
    numpy << (r ? " [" : "[");
    for (int c = 0; c < 4; ++c) numpy << (c ? ", " : "") << t(r, c);
    numpy << (r < 3 ? "],\n" : "]]\n");
  }
  EXPECT_LT(max_abs_diff(sgdicp::parse_transform(numpy.str(), "numpy"), t), 1e-14);
  // Comment lines with numbers in them are ignored: 12 numbers + a comment with 4 more.
  EXPECT_LT(max_abs_diff(sgdicp::parse_transform("# 1 2 3 4\n" + numbers(t, 12, " "), "c"), t),
            1e-14);
  // Exponents and an explicit plus sign.
  EXPECT_LT(
      max_abs_diff(sgdicp::parse_transform("1e0 0 0 +1.5e+1  0 1.0 0 -2E-1  0 0 +1 0", "exponents"),
                   [] {
                     Eigen::Matrix4d e = Eigen::Matrix4d::Identity();
                     e(0, 3) = 15.0;
                     e(1, 3) = -0.2;
                     return e;
                   }()),
      1e-15);
}

TEST(ParseTransform, SixDigitFilesAreProjectedOntoARotation) {
  std::mt19937_64 rng(43);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Matrix4d t = random_rigid(rng, 100.0);
    std::ostringstream s;
    s.precision(6);
    for (int k = 0; k < 12; ++k) s << t(k / 4, k % 4) << ' ';
    const Eigen::Matrix4d parsed = sgdicp::parse_transform(s.str(), "six digits");
    ASSERT_TRUE(sgdicp::is_rigid_transform(parsed, 1e-12));
    ASSERT_LT(max_abs_diff(parsed.topLeftCorner<3, 3>(), t.topLeftCorner<3, 3>()), 1e-5);
  }
}

TEST(ParseTransform, WrongCount) {
  expect_format_error("", "empty text", "0");
  expect_format_error("# only a comment\n", "comment only");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1", "eleven numbers", "11");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 0 0", "thirteen numbers", "13");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 0", "seventeen numbers", "17");
  expect_format_error("1 2 3 4 5", "five numbers", "5");
}

TEST(ParseTransform, NotANumber) {
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 x", "letter at the end", "line 1");
  expect_format_error("1 0 0 0\n0 1 0 0\n0 0 one 0\n", "word on line 3", "line 3");
  expect_format_error("hello world", "text");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 0.0.0", "two dots");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 --1", "double minus");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 1..", "dots");
}

TEST(ParseTransform, NonRigid) {
  expect_format_error("2 0 0 0 0 2 0 0 0 0 2 0", "scaled");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 -1 0", "reflection");
  expect_format_error("1 0.1 0 0 0 1 0 0 0 0 1 0", "shear");
  expect_format_error("0 0 0 0 0 0 0 0 0 0 0 0", "zeros");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 2", "bad last row");
  expect_format_error("1 0 0 0 0 1 0 0 0 0 1 0 1 0 0 1", "bad last row 2");
}

TEST(ParseTransform, NonFinite) {
  expect_format_error("1 0 0 nan 0 1 0 0 0 0 1 0", "nan value");
  expect_format_error("1 0 0 NaN 0 1 0 0 0 0 1 0", "NaN value");
  expect_format_error("1 0 0 inf 0 1 0 0 0 0 1 0", "inf value");
  expect_format_error("1 0 0 -inf 0 1 0 0 0 0 1 0", "minus inf value");
  expect_format_error("1 0 0 1e999 0 1 0 0 0 0 1 0", "overflowing value");
}

TEST(TransformFile, WriteReadRoundTripIsBitExact) {
  // write_transform promises 17 significant digits, "exact round trip" (transform_io.hpp), and
  // parse_transform keeps a matrix that is already a rotation to machine precision bit for bit
  // (it projects only sloppier, e.g. 6-digit, matrices), so `--output` then `--init` reproduces
  // a pose exactly.
  const TempDir dir;
  std::mt19937_64 rng(44);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Matrix4d t = random_rigid(rng, 100.0);
    const fs::path file = dir.path() / ("t" + std::to_string(i) + ".txt");
    sgdicp::write_transform(file, t);
    // The text itself parses back bit-exactly (17 digits).
    std::ifstream in(file);
    Eigen::Matrix4d raw;
    for (int k = 0; k < 16; ++k) in >> raw(k / 4, k % 4);
    ASSERT_TRUE(in) << "4 lines of 4 numbers";
    ASSERT_EQ(raw, t) << "the written text is not exact";
    const Eigen::Matrix4d back = sgdicp::read_transform(file);
    for (int k = 0; k < 16; ++k) {
      ASSERT_EQ(back(k / 4, k % 4), t(k / 4, k % 4))
          << "element " << k << " of transform " << i << " differs by "
          << back(k / 4, k % 4) - t(k / 4, k % 4);
    }
  }
}

TEST(TransformFile, FormatTransformLayout) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t(0, 3) = 0.1;
  const std::string text = sgdicp::format_transform(t);
  // 4 lines of 4 numbers; 0.1 needs all 17 digits to round-trip.
  std::istringstream lines(text);
  std::string line;
  int count = 0;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    double v = 0;
    int n = 0;
    while (fields >> v) ++n;
    EXPECT_EQ(n, 4) << line;
    ++count;
  }
  EXPECT_EQ(count, 4);
  EXPECT_NE(text.find("0.10000000000000001"), std::string::npos) << text;
}

TEST(TransformFile, ReadErrors) {
  const TempDir dir;
  EXPECT_THROW((void)sgdicp::read_transform(dir.path() / "missing.txt"), sgdicp::IoError);
  try {
    (void)sgdicp::read_transform(dir.path() / "missing.txt");
  } catch (const sgdicp::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.txt"), std::string::npos) << e.what();
  }
  // A directory is not a transform file (either error type is acceptable, but an error).
  EXPECT_THROW((void)sgdicp::read_transform(dir.path()), sgdicp::Error);
  // A file with 11 numbers names the file.
  const fs::path bad = dir.path() / "bad.txt";
  {
    std::ofstream out(bad);
    out << "1 0 0 0\n0 1 0 0\n0 0 1\n";
  }
  try {
    (void)sgdicp::read_transform(bad);
    ADD_FAILURE() << "no error for 11 numbers";
  } catch (const sgdicp::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
  }
  // Writing into a folder that does not exist.
  EXPECT_THROW(
      sgdicp::write_transform(dir.path() / "no" / "such" / "dir.txt", Eigen::Matrix4d::Identity()),
      sgdicp::IoError);
}

TEST(ParseTransform, StrictTokens) {
  const std::string rest = " 0 0 0  0 1 0 0  0 0 1 0";  // 11 numbers after the first
  EXPECT_EQ(sgdicp::parse_transform("+1" + rest, "plus")(0, 0), 1.0);
  // One token is one number: "0.0.5" is not 0.0 and .5, "+-1" is not -1.
  for (const std::string bad : {"0.0.5", "+-1", "++1", "1e", "0x1p0", "1.0f", "1-2"}) {
    SCOPED_TRACE(bad);
    expect_format_error(bad + rest, "strict", "expected a number, got '" + bad + "'");
  }
  // 12 numbers once "0.0.5" is no longer split in two: the count error must not come first.
  expect_format_error("1 0 0 0.0.5\n0 1 0 0\n0 0 1", "split", "'0.0.5'");
}

TEST(ParseTransform, NumberEdges) {
  // The identity with the given text as t_x (and r00).
  const auto with_tx = [](const std::string& tx, const std::string& r00 = "1") {
    return r00 + " 0 0 " + tx + "  0 1 0 0  0 0 1 0";
  };
  // Overflow written out in full (1e399) is infinite: rejected, not read as 0.
  expect_format_error(with_tx("1" + std::string(400, '0') + "e-1"), "overflow", "non-finite");
  expect_format_error(with_tx("nan"), "nan", "non-finite");
  expect_format_error(with_tx("-inf"), "inf", "non-finite");
  // Underflow (1e-400) is 0, the subnormals exact, long mantissas correctly rounded.
  EXPECT_EQ(sgdicp::parse_transform(with_tx("0." + std::string(400, '0') + "1e+1"), "u")(0, 3),
            0.0);
  EXPECT_EQ(sgdicp::parse_transform(with_tx("4.9406564584124654e-324"), "s")(0, 3),
            std::numeric_limits<double>::denorm_min());
  const Eigen::Matrix4d T = sgdicp::parse_transform(
      with_tx("0.1" + std::string(600, '0') + "1", "0." + std::string(600, '9')), "long");
  EXPECT_EQ(T(0, 0), 1.0);
  EXPECT_EQ(T(0, 3), 0.1);
}

TEST(TransformFile, NonRegularFilesAreNotRead) {
  const TempDir dir;
  if (!fs::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero";
  const fs::path zero = dir.path() / "zero.txt";
  fs::create_symlink("/dev/zero", zero);
  EXPECT_THROW((void)sgdicp::read_transform(zero), sgdicp::IoError);
  const fs::path big = dir.path() / "big.txt";
  {
    std::ofstream out(big);
    out << std::string(2 << 20, ' ');
  }
  EXPECT_THROW((void)sgdicp::read_transform(big), sgdicp::IoError);
}

}  // namespace
