#include "web/web_assets.h"

#include <algorithm>

namespace cornerpose::web {

const WebAsset* FindWebAsset(std::string_view path) {
  const std::span<const WebAsset> assets = WebAssets();
  const auto it = std::lower_bound(assets.begin(), assets.end(), path,
                                   [](const WebAsset& a, std::string_view p) { return a.path < p; });
  return it != assets.end() && it->path == path ? &*it : nullptr;
}

}  // namespace cornerpose::web
