#include "io/metrics_csv.h"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "io/atomic_file.h"
#include "test_dir.h"

namespace depthbias::io {
namespace {

const char* kArticle = DEPTHBIAS_SOURCE_DIR "/config/data/paper_d455_outdoor.csv";
const char* kHeader12 =
    "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,"
    "hole_rate_pct,valid_pct\n";

std::string ErrorOf(const std::string& text) {
  try {
    ParseMetricsCsv(text, "m.csv");
  } catch (const IoError& e) {
    return e.what();
  }
  return "";
}

TEST(MetricsCsv, ReadsTheArticlesTable) {
  const auto rows = ReadMetricsCsv(kArticle);
  ASSERT_EQ(rows.size(), 128u);
  int daylight = 0;
  for (const auto& r : rows) {
    EXPECT_TRUE(r.ok());
    EXPECT_TRUE(r.light == "daylight" || r.light == "sunset");
    EXPECT_TRUE(r.preset == "HA" || r.preset == "HD");
    EXPECT_NEAR(r.valid_pct + r.hole_rate_pct, 100.0, 0.02);
    EXPECT_TRUE(std::isnan(r.range_m));  // extra columns are empty
    daylight += r.light == "daylight";
  }
  EXPECT_EQ(daylight, 64);
  EXPECT_EQ(rows[0].bag, "article_daylight_emitter-off_4m_0deg_HA");
  EXPECT_DOUBLE_EQ(rows[0].median_m, 3.989);
}

TEST(MetricsCsv, WriteThenReadRoundTripsEveryColumn) {
  records::PanelMetrics m;
  m.bag = "a, b.bag";
  m.light = "daylight";
  m.emitter = "on";
  m.preset = "HA";
  m.distance_m = 4;
  m.angle_deg = 10;
  m.frames = 300;
  m.mean_m = 4.01;
  m.median_m = 4.0;
  m.plane_std_m = 0.01;
  m.hole_rate_pct = 3;
  m.valid_pct = 97;
  m.range_m = 4.06;
  m.azimuth_deg = 9.8;
  m.elevation_deg = -1.0;
  m.normal_tilt_deg = 2;
  m.panel_width_m = 1;
  m.panel_height_m = 1.01;
  m.region_px = 1234;
  m.subpixel_rms_px = 0.07;
  m.temporal_std_m = 0.004;
  m.sigma_d_px = 0.070123456789012;
  records::PanelMetrics failed;
  failed.bag = "broken.bag";
  failed.distance_m = 8;
  failed.angle_deg = 0;
  failed.status = "no_panel";
  failed.message = "no plane found";
  const auto dir = testing::FreshDir("io");
  const std::string path = (dir / "m.csv").string();
  WriteMetricsCsv(path, {m, failed});
  const auto back = ReadMetricsCsv(path);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].bag, m.bag);
  EXPECT_EQ(back[0].temporal_std_m, m.temporal_std_m);
  EXPECT_EQ(back[0].sigma_d_px, m.sigma_d_px);  // exactly
  EXPECT_TRUE(std::isnan(back[1].sigma_d_px));   // an empty cell: not measured
  EXPECT_EQ(back[0].region_px, m.region_px);
  EXPECT_EQ(back[0].range_m, m.range_m);
  EXPECT_FALSE(back[1].ok());
  EXPECT_EQ(back[1].message, "no plane found");
  EXPECT_TRUE(std::isnan(back[1].median_m));
  // The header is DESIGN.md's order.
  const std::string text = ReadFile(path);
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,"
            "hole_rate_pct,valid_pct,range_m,azimuth_deg,elevation_deg,normal_tilt_deg,"
            "panel_width_m,panel_height_m,region_px,subpixel_rms_px,temporal_std_m,sigma_d_px,"
            "status,message");
}

// sigma_d_px is optional: tables without the column (the article's, tables written before it)
// read it as not measured; a cell may be empty or nan; a negative one is refused.
TEST(MetricsCsv, SigmaDColumnIsOptional) {
  const auto old = ParseMetricsCsv(std::string(kHeader12) + "x,d,on,HA,4,0,10,4,4,0.1,1,99\n",
                                   "m.csv");
  ASSERT_EQ(old.size(), 1u);
  EXPECT_TRUE(std::isnan(old[0].sigma_d_px));
  const std::string header =
      std::string(kHeader12).substr(0, std::strlen(kHeader12) - 1) + ",sigma_d_px\n";
  const auto rows = ParseMetricsCsv(header + "x,d,on,HA,4,0,10,4,4,0.1,1,99,0.0712\n" +
                                        "y,d,on,HA,8,0,10,8,8,0.1,1,99,\n" +
                                        "z,d,on,HA,12,0,10,12,12,0.1,1,99,nan\n",
                                    "m.csv");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].sigma_d_px, 0.0712);
  EXPECT_TRUE(std::isnan(rows[1].sigma_d_px));
  EXPECT_TRUE(std::isnan(rows[2].sigma_d_px));
  const auto back = ParseMetricsCsv(FormatMetricsCsv(rows), "back.csv");
  EXPECT_EQ(back[0].sigma_d_px, 0.0712);
  EXPECT_TRUE(std::isnan(back[1].sigma_d_px));
  const std::string e = ErrorOf(header + "x,d,on,HA,4,0,10,4,4,0.1,1,99,-0.07\n");
  EXPECT_NE(e.find("m.csv:2: column 'sigma_d_px'"), std::string::npos) << e;
}

TEST(MetricsCsv, MissingColumnIsNamed) {
  const std::string e = ErrorOf("bag,light,emitter,preset,distance_m\nx,d,on,HA,4\n");
  EXPECT_NE(e.find("m.csv"), std::string::npos) << e;
  EXPECT_NE(e.find("angle_deg"), std::string::npos) << e;
}

TEST(MetricsCsv, NaNInRequiredColumnNamesRowAndColumn) {
  const std::string e = ErrorOf(std::string(kHeader12) + "x,d,on,HA,4,0,10,4,4,0.1,1,99\n" +
                                "y,d,on,HA,8,0,10,8,,0.1,1,99\n");
  EXPECT_NE(e.find("m.csv:3"), std::string::npos) << e;
  EXPECT_NE(e.find("median_m"), std::string::npos) << e;
  const std::string e2 = ErrorOf(std::string(kHeader12) + "x,d,on,HA,4,0,10,4,nan,0.1,1,99\n");
  EXPECT_NE(e2.find("median_m"), std::string::npos) << e2;
  const std::string e3 = ErrorOf(std::string(kHeader12) + "x,d,on,HA,4,zero,10,4,4,0.1,1,99\n");
  EXPECT_NE(e3.find("'zero' is not a number"), std::string::npos) << e3;
}

TEST(MetricsCsv, RowsMeasuredWithoutManifestHaveNoGroundTruth) {
  const auto rows = ParseMetricsCsv(std::string(kHeader12) + "x,,,HA,,,10,4,4,0.1,1,99\n", "m.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_TRUE(std::isnan(rows[0].distance_m));
  EXPECT_TRUE(std::isnan(rows[0].angle_deg));
  EXPECT_DOUBLE_EQ(rows[0].median_m, 4.0);
}

TEST(MetricsCsv, FailedRowsMayLackMeasurements) {
  const auto rows = ParseMetricsCsv(
      "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,median_m,plane_std_m,"
      "hole_rate_pct,valid_pct,status,message\nx,d,on,HA,4,0,,,,,,,no_panel,none found\n",
      "m.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].status, "no_panel");
}

// A header that misspells median_m, followed by an ok row: the column an ok row needs is
// required in the header, and the refusal names the column and the file.
TEST(MetricsCsv, HeaderMissingAColumnThatOkRowsNeedIsRefused) {
  const std::string header =
      "bag,light,emitter,preset,distance_m,angle_deg,frames,mean_m,medain_m,plane_std_m,"
      "hole_rate_pct,valid_pct,status\n";
  const std::string e = ErrorOf(header + "x,d,on,HA,4,0,10,4,4,0.1,1,99,ok\n");
  EXPECT_NE(e.find("m.csv"), std::string::npos) << e;
  EXPECT_NE(e.find("'median_m'"), std::string::npos) << e;
  // Whatever the rows say: a table without the column is refused even when no row is ok.
  const std::string e2 = ErrorOf(header + "x,d,on,HA,4,0,10,4,4,0.1,1,99,no_panel\n");
  EXPECT_NE(e2.find("'median_m'"), std::string::npos) << e2;
}

// A status read from a quoted cell keeps no blanks: "ok\t" is an ok row, so its median is
// required, and the table reads back the same once written.
TEST(MetricsCsv, StatusIsReadWithoutBlanks) {
  const std::string header = std::string(kHeader12).substr(0, std::strlen(kHeader12) - 1) +
                             ",status\n";
  const std::string e = ErrorOf(header + "x,d,on,HA,4,0,10,4,,0.1,1,99,\"ok\t\"\n");
  EXPECT_NE(e.find("median_m"), std::string::npos) << e;
  const auto rows = ParseMetricsCsv(header + "x,d,on,HA,4,0,10,4,4,0.1,1,99,\" ok\t\"\n", "m.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].status, "ok");
}

// Text cells with blanks at either end (spaces or tabs) are quoted when written, so that they
// read back as they were (a tab used to be written bare and trimmed away on reading).
TEST(MetricsCsv, BlanksAtTheEndsOfTextCellsRoundTrip) {
  const auto rows = ParseMetricsCsv(
      std::string(kHeader12) + "\"\tx\",\"d\t\",\" on\",HA,4,0,10,4,4,0.1,1,99\n", "m.csv");
  ASSERT_EQ(rows.size(), 1u);
  const auto back = ParseMetricsCsv(FormatMetricsCsv(rows), "back.csv");
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].bag, "\tx");
  EXPECT_EQ(back[0].light, "d\t");
  EXPECT_EQ(back[0].emitter, " on");
}

}  // namespace
}  // namespace depthbias::io
