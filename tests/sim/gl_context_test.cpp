#include "sim/gl_context.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "core/error.h"

namespace segslam::sim {
namespace {

TEST(GlBackendTest, ParsesAndNamesBackends) {
  EXPECT_EQ(ParseGlBackend("osmesa"), GlBackend::kOsmesa);
  EXPECT_EQ(ParseGlBackend("egl"), GlBackend::kEgl);
  EXPECT_EQ(GlBackendName(GlBackend::kOsmesa), "osmesa");
  EXPECT_EQ(GlBackendName(GlBackend::kEgl), "egl");
}

TEST(GlBackendTest, UnknownBackendThrowsWithTheExpectedMessage) {
  try {
    ParseGlBackend("glx");
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown GL back-end 'glx' (expected osmesa or egl)");
  }
}

TEST(GlContextTest, BothBackendsCreateContexts) {
  for (GlBackend backend : {GlBackend::kOsmesa, GlBackend::kEgl}) {
    GlContext context(backend, 64, 48);
    EXPECT_EQ(context.backend(), backend);
    EXPECT_FALSE(context.renderer().empty());
    EXPECT_NO_THROW(context.MakeCurrent());
  }
}

TEST(GlContextTest, InvalidSizeThrows) {
  EXPECT_THROW(GlContext(GlBackend::kOsmesa, 0, 10), Error);
}

// With no EGL vendor library, creating an EGL context fails with a one-line Error.
// Runs in a fresh process (threadsafe death test) since EGL reads its vendors once.
TEST(GlContextDeathTest, EglFailureIsAOneLineError) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        setenv("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/segslam_no_vendor.json", 1);
        setenv("__EGL_VENDOR_LIBRARY_DIRS", "/nonexistent", 1);
        int code = 1;
        try {
          GlContext context(GlBackend::kEgl, 8, 8);
        } catch (const Error& e) {
          const std::string message = e.what();
          std::fprintf(stderr, "error: %s\n", message.c_str());
          code = message.find('\n') == std::string::npos && message.rfind("EGL", 0) == 0 ? 0
                                                                                         : 2;
        }
        std::exit(code);
      },
      ::testing::ExitedWithCode(0), "error: EGL");
}

}  // namespace
}  // namespace segslam::sim
