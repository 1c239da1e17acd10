// Budget (core/budget.h): one bound for every command's memory and outputs, refused with the
// option that drives the estimate and the budget's own name.
#include <gtest/gtest.h>

#include <cmath>

#include "linesurf/core/budget.h"
#include "linesurf/core/error.h"

using namespace linesurf;

TEST(Budget, RefusesAnEstimateOverItNamingTheOptionAndItself) {
  const Budget b(1, "--max-mb");
  EXPECT_TRUE(b.allows(1024.0 * 1024.0));
  EXPECT_FALSE(b.allows(1024.0 * 1024.0 + 1));
  EXPECT_FALSE(b.allows(std::nan("")));
  try {
    b.require("--views", 3.0 * 1024 * 1024, "writing 3 images");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
    EXPECT_STREQ(e.what(), "--views: writing 3 images needs about 3 MiB, more than --max-mb 1 (raise --max-mb to allow it)");
  }
  EXPECT_NO_THROW(b.require("--views", 1000, "small"));
}

TEST(Budget, ItselfMustBeAPositiveFiniteSize) {
  for (double mb : {0.0, -1.0, std::nan(""), double(INFINITY)}) EXPECT_THROW(Budget{mb}, Error) << mb;
  EXPECT_EQ(Budget(2, "max_mb").name(), "max_mb");
}

TEST(Budget, EstimatesGrowWithTheirWork) {
  EXPECT_GT(renderViewBytes(2048, 2048, 4), renderViewBytes(1024, 1024, 4));
  // 10,000 views of 2048 x 2048 are about 160 GiB of PNG at most.
  EXPECT_NEAR(10000 * pngFileBytes(2048, 2048) / std::pow(1024.0, 3), 156.25, 0.1);
  EXPECT_GT(modelFileBytes(1000, 0, true), modelFileBytes(1000, 0, false));
  EXPECT_GT(pointGeometryBytes(1000, 24), pointGeometryBytes(1000, 12));
}
