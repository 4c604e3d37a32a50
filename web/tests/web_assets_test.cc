// The embedded web view: what the server's HTTP port will serve.
#include "web/web_assets.h"

#include <string>

#include "gtest/gtest.h"

namespace cornerpose::web {
namespace {

TEST(WebAssets, IndexIsHtmlAndSorted) {
  const WebAsset* index = FindWebAsset("/index.html");
  ASSERT_NE(index, nullptr);
  EXPECT_EQ(index->content_type, "text/html; charset=utf-8");
  EXPECT_NE(index->body.find("<title>cornerpose"), std::string_view::npos);
  const auto assets = WebAssets();
  for (size_t i = 1; i < assets.size(); ++i) EXPECT_LT(assets[i - 1].path, assets[i].path);
  EXPECT_EQ(FindWebAsset("/nope.js"), nullptr);
  EXPECT_EQ(FindWebAsset(""), nullptr);
}

#if CORNERPOSE_WEB_BUNDLED
TEST(WebAssets, BundleHoldsThePageAndThreeJs) {
  const WebAsset* index = FindWebAsset("/index.html");
  ASSERT_NE(index, nullptr);
  // The page loads only the server's own files: no other host.
  EXPECT_NE(index->body.find("src=\"/assets/main.js\""), std::string_view::npos);
  EXPECT_EQ(index->body.find("http://"), std::string_view::npos);
  EXPECT_EQ(index->body.find("https://"), std::string_view::npos);
  const WebAsset* js = FindWebAsset("/assets/main.js");
  ASSERT_NE(js, nullptr);
  EXPECT_EQ(js->content_type, "text/javascript; charset=utf-8");
  // three.js is in the bundle (its WebGL renderer), not fetched from a CDN.
  EXPECT_GT(js->body.size(), 100000u);
  EXPECT_NE(js->body.find("WebGLRenderer"), std::string_view::npos);
  EXPECT_NE(js->body.find("/api/sources"), std::string_view::npos);
  const WebAsset* css = FindWebAsset("/assets/main.css");
  ASSERT_NE(css, nullptr);
  EXPECT_EQ(css->content_type, "text/css; charset=utf-8");
}
#endif

}  // namespace
}  // namespace cornerpose::web
