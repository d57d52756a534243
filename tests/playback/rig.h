// Test helper: a synthetic rigged character for playback tests — the two tubes of
// tests/runtime/asset_builder.h (B 10 units above A), tube A's vertices on joint 0, B's on joint 1, and a
// clip "lower" that translates B's node from 0 to (0, 0, -12) over 1 s; with its asset.
#pragma once

#include <doctest/doctest.h>

#include "runtime/asset_builder.h"
#include "spherechain/import/types.h"

namespace spherechain::test {

struct Rig {
  spherechain::test::AlignedBytes bytes;
  spherechain::runtime::AssetView view;
  spherechain::import::Mesh mesh;
  spherechain::test::AssetData data;
};

/// Tubes apart (B 10 units above A), B's vertices on joint 1, A's on joint 0; clip "lower": B's node
/// translates from 0 to (0, 0, -12) over 1 s.
inline void MakeRig(Rig* r) {
  spherechain::test::Mesh m;
  r->data = spherechain::test::TwoTubes(false, &m);
  r->mesh.positions = m.positions;
  r->mesh.indices = m.triangles;
  spherechain::import::Skin skin;
  skin.source = "test";
  skin.nodes.resize(3);
  skin.nodes[0].name = "root";
  skin.nodes[1].name = "tube_a";
  skin.nodes[1].parent = 0;
  skin.nodes[2].name = "tube_b";
  skin.nodes[2].parent = 0;
  skin.joints.resize(2);
  skin.joints[0].node = 1;
  skin.joints[1].node = 2;
  const uint32_t V = m.vertex_count();
  for (uint32_t v = 0; v < V; ++v) {
    skin.weight_offsets.push_back(v);
    skin.weight_joints.push_back(v < V / 2 ? 0 : 1);
    skin.weights.push_back(1.0f);
  }
  skin.weight_offsets.push_back(V);
  r->mesh.skin = skin;
  spherechain::import::Clip clip;
  clip.name = "lower";
  clip.duration_s = 1.0f;
  spherechain::import::Channel ch;
  ch.node = 2;
  ch.path = spherechain::import::Channel::Path::kTranslation;
  ch.times = {0.0f, 1.0f};
  ch.values = {0, 0, 0, 0, 0, -12};
  clip.channels.push_back(ch);
  r->mesh.clips.push_back(clip);
  r->bytes = spherechain::test::Serialize(r->data);
  REQUIRE(spherechain::runtime::LoadAsset(r->bytes.data(), r->bytes.size, &r->view) == spherechain::runtime::Status::kOk);
}

}  // namespace spherechain::test
