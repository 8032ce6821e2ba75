// The map's ray walk (src/ray_keys.h) against OctoMap's own computeRayKeys(): the same keys in the
// same order, and the same answer at the tree's bounds, over random rays, rays along the axes and
// the diagonals, rays from and through voxel corners, and rays as the map casts them.
#include "ray_keys.h"

#include <octomap/OcTree.h>

#include <gtest/gtest.h>

#include <cstddef>
#include <random>
#include <vector>

namespace {

using multislit::detail::RayKeys;
using octomap::point3d;

/// Compares one ray; counts the rays and the keys compared.
struct Compare {
  explicit Compare(const octomap::OcTree& t) : tree(t), walk(t) {}
  const octomap::OcTree& tree;
  RayKeys walk;
  octomap::KeyRay stock;
  std::size_t rays = 0, keys = 0, refused = 0;

  void operator()(const point3d& origin, const point3d& end) {
    std::vector<octomap::OcTreeKey> ours;
    const bool ok = walk.walk(origin, end, [&](const octomap::OcTreeKey& k) { ours.push_back(k); });
    ASSERT_EQ(ok, tree.computeRayKeys(origin, end, stock)) << origin << " -> " << end;
    if (!ok) {
      ASSERT_TRUE(ours.empty());
      ++refused;
      return;
    }
    ASSERT_EQ(ours.size(), stock.size()) << origin << " -> " << end;
    std::size_t i = 0;
    for (const octomap::OcTreeKey& k : stock) ASSERT_EQ(ours[i++], k) << origin << " -> " << end;
    ++rays;
    keys += ours.size();
  }
};

class RayKeysTest : public ::testing::TestWithParam<double> {};

TEST_P(RayKeysTest, GivesOctoMapsKeysForRandomRays) {
  const octomap::OcTree tree(GetParam());
  Compare compare(tree);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> near(-0.5f, 0.5f), far(-300.0f, 300.0f);
  for (int i = 0; i < 40000; ++i) {
    const point3d a(near(rng), near(rng), near(rng));
    compare(a, a + point3d(near(rng), near(rng), near(rng)));
    if (HasFatalFailure()) return;
  }
  for (int i = 0; i < 4000; ++i) {  // far from the origin: fewer bits below the voxel size
    const point3d a(far(rng), far(rng), near(rng));
    compare(a, a + point3d(near(rng), near(rng), near(rng)) * 0.2f);
    if (HasFatalFailure()) return;
  }
  EXPECT_EQ(compare.rays, 44000u);
  EXPECT_GT(static_cast<double>(compare.keys), 0.3 / GetParam() * 44000);
}

TEST_P(RayKeysTest, GivesOctoMapsKeysAlongAxesAndThroughCorners) {
  const double res = GetParam();
  const octomap::OcTree tree(res);
  Compare compare(tree);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> cell(-20, 20);
  std::uniform_real_distribution<float> near(-0.3f, 0.3f);
  const auto corner = [&] {  // a voxel corner, as near as float holds it
    return point3d(static_cast<float>(cell(rng) * res), static_cast<float>(cell(rng) * res),
                   static_cast<float>(cell(rng) * res));
  };
  for (int i = 0; i < 20000; ++i) {
    const point3d a = corner();
    compare(a, corner());  // corner to corner: diagonals through corners, ties between axes
    const point3d b(near(rng), near(rng), near(rng));
    point3d along = b;  // along each axis in turn, and along a face diagonal
    along(i % 3) += near(rng);
    compare(b, along);
    along((i + 1) % 3) += along(i % 3) - b(i % 3);
    compare(b, along);
    compare(a, a + point3d(1, 1, 1) * static_cast<float>(cell(rng) * res));  // the space diagonal
    if (HasFatalFailure()) return;
  }
  EXPECT_EQ(compare.rays, 80000u);
  EXPECT_GT(compare.keys, 10u * compare.rays);
}

TEST_P(RayKeysTest, GivesOctoMapsKeysForTheMapsRaysAndBounds) {
  const double res = GetParam();
  const octomap::OcTree tree(res);
  Compare compare(tree);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> floor(-2.0f, 2.0f), light(-1.0f, 1.0f);
  // As the map casts them: from free_height (6 voxels) down to half a voxel above a floor point,
  // toward a projector 0.3 to 0.7 m above the floor.
  for (int i = 0; i < 20000; ++i) {
    const point3d p(floor(rng), floor(rng), 0.0f);
    const point3d to_light = point3d(light(rng), light(rng), 0.5f + 0.2f * light(rng));
    compare(p + to_light * static_cast<float>(6 * res / to_light.z()),
            p + to_light * static_cast<float>(0.5 * res / to_light.z()));
    if (HasFatalFailure()) return;
  }
  const auto edge = static_cast<float>(32768 * res);  // the tree holds [-edge, edge)
  compare(point3d(0, 0, 0), point3d(1.01f * edge, 0, 0));
  compare(point3d(-1.01f * edge, 0, 0), point3d(0, 0.1f, 0));
  compare(point3d(0, 0, 0), point3d(0, 0, -2 * edge));
  compare(point3d(0.99f * edge, 0, 0), point3d(-0.99f * edge, 0, 0));  // across the whole tree
  compare(point3d(0.001f, 0, 0), point3d(0.002f, 0, 0));               // one voxel: no keys
  EXPECT_EQ(compare.refused, 3u);
  EXPECT_EQ(compare.rays, 20002u);
  EXPECT_GT(compare.keys, 4u * compare.rays);
}

INSTANTIATE_TEST_SUITE_P(Resolutions, RayKeysTest, ::testing::Values(0.01, 0.013, 0.05, 0.1));

}  // namespace
