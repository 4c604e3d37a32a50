// The web view's files (web/: index.html and the bundled assets), compiled
// into the binary so the server needs no files beside it and loads nothing
// from elsewhere. Built by web/CMakeLists.txt: the esbuild bundle when npm
// is present, otherwise a page that says the view was built without npm.
#pragma once

#include <span>
#include <string_view>

namespace cornerpose::web {

struct WebAsset {
  // URL path, from the root: "/index.html", "/assets/main.js".
  std::string_view path;
  // HTTP Content-Type.
  std::string_view content_type;
  std::string_view body;
};

// Every embedded file, sorted by path.
std::span<const WebAsset> WebAssets();

// The asset at `path`, or nullptr.
const WebAsset* FindWebAsset(std::string_view path);

}  // namespace cornerpose::web
