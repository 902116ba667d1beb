// The load balancer's decisions (sim/src/threads/load_balancer.hpp), on made-up busy times: the shares follow the
// measured speeds, stay put when the threads are even (or the gain is too small to pay for a new plan), and
// are left alone when the user gave weights. Whether the partition changes the trajectory is test_dynamics'
// concern (it does not).
#include "threads/load_balancer.hpp"
#include "pmfrag/run/run.hpp"
#include "threads/team.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace pmfrag::detail {
namespace {

constexpr long plate = 2698;  // the paper's slit plate

// busy[t * 8]: each thread's busy time, one cache line apart as Leapfrog keeps them
std::vector<double> busy_per_thread(double t0, double t1) {
  std::vector<double> b(16, 0.0);
  b[0] = t0, b[8] = t1;
  return b;
}

TEST(LoadBalancer, SharesFollowTheMeasuredSpeeds) {
  Team team(2);
  const std::vector<long> equal = team.bounds(plate);
  ASSERT_EQ(equal, (std::vector<long>{0, 1344, plate}));  // the nearest grain to half
  LoadBalancer lb;
  // thread 1 takes twice as long for its share: after a full window thread 0 gets ~2/3 of the particles
  const auto busy = busy_per_thread(1.0e4, 2.0e4);
  lb.add(team, equal, busy.data(), 8, LoadBalancer::window / 2);
  EXPECT_EQ(team.bounds(plate), equal) << "no decision before the window is full";
  EXPECT_EQ(lb.room(), LoadBalancer::window / 2);
  lb.add(team, equal, busy.data(), 8, LoadBalancer::window / 2);
  const std::vector<long> moved = team.bounds(plate);
  // speeds 1344 / 1e4 and 1354 / 2e4 particles per unit: thread 0's share 0.665 x 2698 = 1794 -> 28 grains
  EXPECT_EQ(moved, (std::vector<long>{0, 1792, plate}));
  // measured again on the new shares, now even: they stay
  const auto even = busy_per_thread(1.5e4, 1.5e4);
  lb.add(team, moved, even.data(), 8, LoadBalancer::window);
  EXPECT_EQ(team.bounds(plate), moved);
}

TEST(LoadBalancer, SmallGainsDoNotMoveTheShares) {
  Team team(2);
  const std::vector<long> equal = team.bounds(plate);
  LoadBalancer lb;
  // 2 % apart: one grain (64 particles, 4.7 % of a share) is the least move, and it would not pay 3 %
  const auto busy = busy_per_thread(1.0e4, 1.02e4);
  lb.add(team, equal, busy.data(), 8, LoadBalancer::window);
  EXPECT_EQ(team.bounds(plate), equal);
}

TEST(LoadBalancer, GivenWeightsAreKept) {
  Team team(2);
  team.set_fixed_weights({1.0, 3.0});
  const std::vector<long> given = team.bounds(plate);
  EXPECT_EQ(given, (std::vector<long>{0, 704, plate}));  // a quarter, to the nearest grain
  LoadBalancer lb;
  const auto busy = busy_per_thread(1.0e4, 3.0e4);
  lb.add(team, given, busy.data(), 8, 2 * LoadBalancer::window);
  EXPECT_EQ(team.bounds(plate), given);
}

}  // namespace
}  // namespace pmfrag::detail
