// The Saltelli row layout (engine/estimators/saltelli_layout.h) against SALib's row order written out
// by hand: the estimator's row lookups and the design's column choice must both follow it.
#include "engine/estimators/saltelli_layout.h"

#include <gtest/gtest.h>

namespace gesweep {
namespace {

TEST(SaltelliLayout, FollowsSalibsRowOrder) {
  const SaltelliLayout with{3, 4, true};
  EXPECT_EQ(with.BlockSize(), 8);  // 2D+2
  EXPECT_EQ(with.RowCount(), 32u);
  EXPECT_EQ(with.RowA(1), 8u);
  EXPECT_EQ(with.RowAB(1, 0), 9u);
  EXPECT_EQ(with.RowAB(1, 2), 11u);
  EXPECT_EQ(with.RowBA(1, 0), 12u);
  EXPECT_EQ(with.RowBA(1, 2), 14u);
  EXPECT_EQ(with.RowB(1), 15u);
  EXPECT_EQ(with.BlockOfRow(15), 1);
  EXPECT_EQ(with.BlockOfRow(16), 2);
  const SaltelliLayout without{3, 4, false};
  EXPECT_EQ(without.BlockSize(), 5);  // D+2
  EXPECT_EQ(without.RowB(0), 4u);
  EXPECT_EQ(without.RowAB(2, 1), 12u);
}

TEST(SaltelliBlockRows, IsTwoDPlusTwoOrDPlusTwo) {
  EXPECT_EQ(SaltelliBlockRows(1, false), 3);
  EXPECT_EQ(SaltelliBlockRows(1, true), 4);
  EXPECT_EQ(SaltelliBlockRows(7, false), 9);
  EXPECT_EQ(SaltelliBlockRows(7, true), 16);
  // Past an int: a design of 2^40 base samples still counts its rows in 64 bits.
  EXPECT_EQ(SaltelliBlockRows(1000, true) << 40, std::int64_t{2002} << 40);
}

TEST(SaltelliTakesB, SelectsTheColumnsOfEachRowKind) {
  // D = 2 with second order, SALib's block: A, AB1, AB2, BA1, BA2, B; 1 marks a column from B.
  const bool expected[6][2] = {{false, false}, {true, false}, {false, true},
                               {false, true},  {true, false}, {true, true}};
  for (int row = 0; row < 6; ++row) {
    for (int column = 0; column < 2; ++column) {
      EXPECT_EQ(SaltelliTakesB(2, true, row, column), expected[row][column])
          << "row " << row << " column " << column;
    }
  }
  // Without second order: A, AB1, AB2, B.
  const bool first_only[4][2] = {{false, false}, {true, false}, {false, true}, {true, true}};
  for (int row = 0; row < 4; ++row) {
    for (int column = 0; column < 2; ++column) {
      EXPECT_EQ(SaltelliTakesB(2, false, row, column), first_only[row][column]) << "row " << row;
    }
  }
}

TEST(SaltelliTakesB, AgreesWithTheLayoutsRowLookups) {
  for (bool second_order : {false, true}) {
    const SaltelliLayout layout{4, 3, second_order};
    for (int j = 0; j < layout.base_samples; ++j) {
      const auto in_block = [&](std::size_t row) { return static_cast<std::int64_t>(row - layout.RowA(j)); };
      for (int column = 0; column < 4; ++column) {
        EXPECT_FALSE(SaltelliTakesB(4, second_order, in_block(layout.RowA(j)), column));
        EXPECT_TRUE(SaltelliTakesB(4, second_order, in_block(layout.RowB(j)), column));
        for (int i = 0; i < 4; ++i) {
          EXPECT_EQ(SaltelliTakesB(4, second_order, in_block(layout.RowAB(j, i)), column), column == i);
          if (second_order) {
            EXPECT_EQ(SaltelliTakesB(4, second_order, in_block(layout.RowBA(j, i)), column), column != i);
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace gesweep
