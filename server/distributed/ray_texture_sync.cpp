#include "distributed/ray_texture_sync.h"

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace peakcast::distributed {
namespace {

// Keeps at most kKeptRayTextures, the oldest first out; the same calls on every rank.
template <class Map>
void keep(Map& m, std::deque<uint64_t>& order, uint64_t lineage) {
  order.push_back(lineage);
  while (order.size() > kKeptRayTextures) {
    m.erase(order.front());
    order.pop_front();
  }
}

}  // namespace

nlohmann::json RayTextureSender::message(const RayTextureSpec& spec) {
  nlohmann::json j = {{"lineage", spec.lineage}};
  auto it = sent_.find(spec.lineage);
  const bool whole = it == sent_.end() || it->second > spec.strokes.size();
  if (it != sent_.end() && whole) {  // not continued: the workers start it again
    sent_.erase(it);
    it = sent_.end();
  }
  const size_t from = whole ? 0 : it->second;
  j["from"] = from;
  j["whole"] = whole;
  if (whole) {
    j["mapping"] = spec.mapping == RayTextureMapping::View ? "view" : "volume";
    j["size"] = {spec.width, spec.height};
    if (spec.image) {
      const auto* bytes = reinterpret_cast<const uint8_t*>(spec.image->texels.data());
      j["png"] = spec.png;
      j["image"] =
          nlohmann::json::binary(std::vector<uint8_t>(bytes, bytes + spec.image->texels.size() * sizeof(float)));
    }
  }
  nlohmann::json strokes = nlohmann::json::array();
  for (size_t k = from; k < spec.strokes.size(); ++k) strokes.push_back(to_json(spec.strokes[k]));
  j["strokes"] = std::move(strokes);
  if (it == sent_.end()) keep(sent_, order_, spec.lineage);
  sent_[spec.lineage] = spec.strokes.size();
  return j;
}

std::shared_ptr<const RayTextureSpec> RayTextureReceiver::apply(const nlohmann::json& m) {
  const uint64_t lineage = m.at("lineage");
  const size_t from = m.at("from");
  RayTextureSpec spec;
  auto it = specs_.find(lineage);
  if (m.at("whole").get<bool>()) {
    if (it != specs_.end()) {  // started again: a new lineage here too
      specs_.erase(it);
      it = specs_.end();
    }
    nlohmann::json base = {{"mapping", m.at("mapping")}, {"size", m.at("size")}};
    spec = parse_ray_texture(base);  // a lineage of this rank's
    if (m.contains("image")) {
      const auto& bytes = m.at("image").get_binary();
      auto image = std::make_shared<RayTextureImage>();
      image->width = spec.width;
      image->height = spec.height;
      image->texels.resize(bytes.size() / sizeof(float));
      if (image->texels.size() != size_t(spec.width) * size_t(spec.height) * 3)
        throw std::runtime_error("ray texture: the image's texels do not fit its size");
      std::memcpy(image->texels.data(), bytes.data(), image->texels.size() * sizeof(float));
      spec.image = std::move(image);
      spec.png = m.at("png");
    }
  } else {
    if (it == specs_.end() || it->second->strokes.size() != from)
      throw std::runtime_error(
          "ray texture " + std::to_string(lineage) + ": this rank holds " +
          (it == specs_.end() ? std::string("none") : std::to_string(it->second->strokes.size()) + " strokes") +
          ", rank 0 continues from " + std::to_string(from));
    spec = *it->second;
  }
  const auto& strokes = m.at("strokes");
  for (size_t k = 0; k < strokes.size(); ++k)
    spec.strokes.push_back(parse_stroke(strokes[k], "ray_texture.strokes[" + std::to_string(from + k) + "]"));
  count_work(spec);
  auto out = std::make_shared<const RayTextureSpec>(std::move(spec));
  if (it == specs_.end()) keep(specs_, order_, lineage);
  specs_[lineage] = out;
  return out;
}

}  // namespace peakcast::distributed
