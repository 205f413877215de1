// The bounded hull (physics/src/convex.hpp) collides exactly as the dConvex it
// wraps, and its box for the spaces holds the convex's own.
#include "convex.hpp"

#include <gtest/gtest.h>
#include <ode/ode.h>

#include <array>
#include <random>
#include <vector>

namespace canhil::physics {
namespace {

class BoundedHullTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dInitODE2(0);
    world_ = dWorldCreate();
    body_ = dBodyCreate(world_);
    // A robot's back piece: an off-centre prism, so the offset matters.
    shape_ = make_prism(notched_disc(0.26, 0.2, 0.12).front(), -0.3, 0.3);
    bounded_ = shape_.create(nullptr, body_);
    plain_ = dCreateConvex(nullptr, shape_.planes.data(), shape_.plane_count, shape_.points.data(), shape_.point_count,
                           shape_.polygons.data());
    dGeomSetBody(plain_, body_);
    dGeomSetOffsetPosition(plain_, shape_.offset[0], shape_.offset[1], shape_.offset[2]);
    other_body_ = dBodyCreate(world_);
    other_shape_ = make_frustum(0.2, 0.15, -0.2, 0.2, 16);
    other_bounded_ = other_shape_.create(nullptr, other_body_);
    other_plain_ = dCreateConvex(nullptr, other_shape_.planes.data(), other_shape_.plane_count,
                                 other_shape_.points.data(), other_shape_.point_count, other_shape_.polygons.data());
    dGeomSetBody(other_plain_, other_body_);
    dGeomSetOffsetPosition(other_plain_, other_shape_.offset[0], other_shape_.offset[1], other_shape_.offset[2]);
    ball_ = dCreateSphere(nullptr, 0.11);
    ground_ = dCreatePlane(nullptr, 0, 0, 1, 0);
  }
  void TearDown() override {  // ODE stays initialised: the hull's geom class is registered once a process
    for (dGeomID g : {bounded_, plain_, other_bounded_, other_plain_, ball_, ground_}) dGeomDestroy(g);
    dWorldDestroy(world_);
  }

  // A pose near the origin, tilted by up to `tilt` rad about a random axis.
  void place(dBodyID b, std::mt19937& rng, double spread, double tilt) {
    std::uniform_real_distribution<double> u(-1, 1);
    dBodySetPosition(b, spread * u(rng), spread * u(rng), 0.3 + 0.1 * u(rng));
    dMatrix3 yaw;
    dMatrix3 lean;
    dMatrix3 r;
    dRFromAxisAndAngle(yaw, 0, 0, 1, 3.2 * u(rng));
    dRFromAxisAndAngle(lean, u(rng), u(rng), 0.01, tilt * u(rng));
    dMultiply0_333(r, lean, yaw);
    dBodySetRotation(b, r);
  }

  static std::vector<dContactGeom> contacts(int n, const std::array<dContactGeom, 8>& c) {
    return {c.begin(), c.begin() + n};
  }

  // The same contacts, bit for bit (positions, normals, depths).
  static void expect_same(const std::vector<dContactGeom>& x, const std::vector<dContactGeom>& y, int trial) {
    ASSERT_EQ(x.size(), y.size()) << "trial " << trial;
    for (std::size_t i = 0; i < x.size(); ++i) {
      for (std::size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(x[i].pos[k], y[i].pos[k]) << "trial " << trial << " contact " << i;
        EXPECT_EQ(x[i].normal[k], y[i].normal[k]) << "trial " << trial << " contact " << i;
      }
      EXPECT_EQ(x[i].depth, y[i].depth) << "trial " << trial;
    }
  }

  dWorldID world_ = nullptr;
  dBodyID body_ = nullptr;
  dBodyID other_body_ = nullptr;
  ConvexShape shape_;
  ConvexShape other_shape_;
  dGeomID bounded_ = nullptr;
  dGeomID plain_ = nullptr;
  dGeomID other_bounded_ = nullptr;
  dGeomID other_plain_ = nullptr;
  dGeomID ball_ = nullptr;
  dGeomID ground_ = nullptr;
};

TEST_F(BoundedHullTest, ItsBoxHoldsTheConvexsOwnBoxInEveryPose) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    place(body_, rng, 5, trial % 2 == 0 ? 0.3 : 3.0);
    dReal loose[6];
    dReal exact[6];
    dGeomGetAABB(bounded_, loose);
    dGeomGetAABB(plain_, exact);
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_LE(loose[2 * k], exact[2 * k]) << "trial " << trial << " axis " << k;
      EXPECT_GE(loose[2 * k + 1], exact[2 * k + 1]) << "trial " << trial << " axis " << k;
    }
    // Upright, it is no looser than the bounding cylinder needs.
    if (trial == 0) {
      dMatrix3 upright;
      dRSetIdentity(upright);
      dBodySetRotation(body_, upright);
      dGeomGetAABB(bounded_, loose);
      EXPECT_NEAR(loose[5] - loose[4], 0.6, 1e-12);
    }
  }
}

TEST_F(BoundedHullTest, CollidesAsTheConvexWithABallAHullAndTheGroundInEitherOrder) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  int touching = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    place(body_, rng, 0.05, 0.2);
    place(other_body_, rng, 0.45, 0.2);
    dGeomSetPosition(ball_, 0.4 * u(rng), 0.4 * u(rng), 0.1 + 0.3 * u(rng));
    dBodySetPosition(body_, dBodyGetPosition(body_)[0], dBodyGetPosition(body_)[1], 0.2 + 0.15 * u(rng));
    std::array<dContactGeom, 8> a{};
    std::array<dContactGeom, 8> b{};
    const auto flags = static_cast<int>(a.size());
    const int skip = sizeof(dContactGeom);
    for (dGeomID other : {ball_, ground_}) {
      const int n = collide_hulls(bounded_, other, flags, a.data(), skip);
      const int m = dCollide(plain_, other, flags, b.data(), skip);
      expect_same(contacts(n, a), contacts(m, b), trial);
      const int n2 = collide_hulls(other, bounded_, flags, a.data(), skip);
      const int m2 = dCollide(other, plain_, flags, b.data(), skip);
      expect_same(contacts(n2, a), contacts(m2, b), trial);
      if (n > 0) {
        ++touching;
        EXPECT_EQ(a[0].g1, other) << "the contacts name the geoms given";
        EXPECT_EQ(a[0].g2, bounded_);
      }
    }
    const int n = collide_hulls(bounded_, other_bounded_, flags, a.data(), skip);
    const int m = dCollide(plain_, other_plain_, flags, b.data(), skip);
    expect_same(contacts(n, a), contacts(m, b), trial);
    touching += n > 0 ? 1 : 0;
  }
  EXPECT_GT(touching, 300) << "the trials must touch often enough to compare contacts";
}

TEST_F(BoundedHullTest, AnyOtherPairIsLeftToOdeAndDestroyingItDestroysItsHull) {
  EXPECT_NE(hull_of(bounded_), nullptr);
  EXPECT_EQ(hull_of(plain_), nullptr);
  EXPECT_EQ(hull_of(ball_), nullptr);
  std::array<dContactGeom, 8> a{};
  dGeomSetPosition(ball_, 0, 0, 0.05);
  EXPECT_EQ(collide_hulls(ball_, ground_, 8, a.data(), sizeof(dContactGeom)), 1);
  // A second one on the body, destroyed: its hull goes with it (the
  // sanitized build reports a leak otherwise), and the first is untouched.
  dGeomID extra = shape_.create(nullptr, body_);
  ASSERT_NE(hull_of(extra), nullptr);
  dGeomDestroy(extra);
  EXPECT_NE(hull_of(bounded_), nullptr);
}

}  // namespace
}  // namespace canhil::physics
