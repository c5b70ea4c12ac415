// The kernels fast_kernels.cpp installs into SUNDIALS against SUNDIALS' own
// serial and dense implementations: every operation CVODES calls, at each
// state count compiled in (even sizes 4..12) and on the run-time-length path
// (other sizes), with the aliasing CVODES uses (outputs that are inputs).
#include "../../src/sim/fast_kernels.h"

#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "../../src/sim/cvode_handles.h"

namespace pneumaid::internal {
namespace {

constexpr int kArray = 5;  // vectors per vector array (CVODES: one per sensitivity)

// One vector of each kind (SUNDIALS' kernels, ours) per slot, same values.
class KernelsTest : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    SUNContext raw = nullptr;
    ASSERT_EQ(SUNContext_Create(nullptr, &raw), 0);
    context_.reset(raw);
    n_ = GetParam();
    reference_.reset(N_VNew_Serial(n_, context_.get()));
    ASSERT_EQ(N_VEnableFusedOps_Serial(reference_.get(), SUNTRUE), 0);
    fast_.reset(N_VNew_Serial(n_, context_.get()));
    ASSERT_EQ(N_VEnableFusedOps_Serial(fast_.get(), SUNTRUE), 0);
    InstallFastVectorKernels(fast_.get());
    for (int k = 0; k < kSlots; ++k) {
      slots_[0].emplace_back(N_VClone(reference_.get()));
      slots_[1].emplace_back(N_VClone(fast_.get()));  // clones inherit the kernels
      for (int i = 0; i < n_; ++i) {
        const double value = Random();
        NV_Ith_S(slots_[0][k].get(), i) = value;
        NV_Ith_S(slots_[1][k].get(), i) = value;
      }
    }
  }

  double Random() { return uniform_(rng_); }

  // Slot k of kind 0 (SUNDIALS) or 1 (ours).
  N_Vector V(int kind, int k) { return slots_[kind][k].get(); }
  std::vector<N_Vector> Array(int kind, int first) {
    std::vector<N_Vector> array;
    for (int k = 0; k < kArray; ++k) array.push_back(V(kind, first + k));
    return array;
  }

  // Every slot equal between the two kinds (the same arithmetic in the same
  // order gives the same bits; a few ulps of slack for contraction).
  void ExpectSlotsEqual(const char* what) {
    for (int k = 0; k < kSlots; ++k) {
      for (int i = 0; i < n_; ++i) {
        const double expected = NV_Ith_S(V(0, k), i), actual = NV_Ith_S(V(1, k), i);
        ASSERT_NEAR(actual, expected, 1e-14 * (1 + std::fabs(expected)))
            << what << ": n = " << n_ << ", slot " << k << ", element " << i;
      }
    }
  }

  static constexpr int kSlots = 4 * kArray;
  ContextPtr context_;
  int n_ = 0;
  VectorPtr reference_, fast_;
  std::vector<VectorPtr> slots_[2];
  std::mt19937 rng_{7};
  std::uniform_real_distribution<double> uniform_{0.5, 2.0};
};

TEST_P(KernelsTest, ElementwiseOperationsMatchSundials) {
  for (int kind = 0; kind < 2; ++kind) {
    N_VLinearSum(0.3, V(kind, 0), -1.7, V(kind, 1), V(kind, 2));
    N_VLinearSum(1.0, V(kind, 3), 1.0, V(kind, 4), V(kind, 3));  // the predictor's x += y
    N_VLinearSum(2.5, V(kind, 5), 1.0, V(kind, 6), V(kind, 6));  // y += a x
    N_VScale(-0.4, V(kind, 7), V(kind, 7));
    N_VProd(V(kind, 8), V(kind, 9), V(kind, 10));
    N_VDiv(V(kind, 10), V(kind, 11), V(kind, 11));
    N_VAbs(V(kind, 7), V(kind, 12));
    N_VInv(V(kind, 12), V(kind, 13));
    N_VAddConst(V(kind, 13), 0.25, V(kind, 14));
    N_VConst(3.0, V(kind, 15));
  }
  ExpectSlotsEqual("elementwise");
  EXPECT_DOUBLE_EQ(N_VWrmsNorm(V(1, 0), V(1, 1)), N_VWrmsNorm(V(0, 0), V(0, 1)));
  EXPECT_DOUBLE_EQ(N_VMaxNorm(V(1, 2)), N_VMaxNorm(V(0, 2)));
}

TEST_P(KernelsTest, FusedOperationsMatchSundials) {
  for (int count = 1; count <= 6; ++count) {
    std::vector<double> c(static_cast<size_t>(std::max(count, 2)));  // ScaleAddMulti takes 2
    for (double& value : c) value = Random() - 1.0;
    for (int kind = 0; kind < 2; ++kind) {
      std::vector<N_Vector> x;
      for (int k = 0; k < count; ++k) x.push_back(V(kind, k));
      N_VLinearCombination(count, c.data(), x.data(), V(kind, 0));  // z aliases x[0]
      N_VLinearCombination(count, c.data(), x.data(), V(kind, 10));
      std::vector<N_Vector> y = {V(kind, 11), V(kind, 12)}, z = {V(kind, 13), V(kind, 12)};
      N_VScaleAddMulti(2, c.data(), V(kind, 1), y.data(), z.data());  // z[1] aliases y[1]
    }
    ExpectSlotsEqual("fused");
  }
}

TEST_P(KernelsTest, VectorArrayOperationsMatchSundials) {
  double c[kArray] = {0.5, -1.5, 2.0, 0.25, -0.75};
  for (int kind = 0; kind < 2; ++kind) {
    std::vector<N_Vector> x = Array(kind, 0), y = Array(kind, kArray), z = Array(kind, 2 * kArray);
    N_VLinearSumVectorArray(kArray, 0.7, x.data(), -0.2, y.data(), z.data());
    N_VLinearSumVectorArray(kArray, 1.0, x.data(), 1.0, y.data(), x.data());   // predictor
    N_VLinearSumVectorArray(kArray, 1.3, y.data(), 1.0, z.data(), z.data());   // z += a y
    N_VLinearSumVectorArray(kArray, 1.0, z.data(), -0.6, y.data(), z.data());  // z += b y
    N_VScaleVectorArray(kArray, c, y.data(), y.data());
    std::vector<N_Vector> w = Array(kind, 3 * kArray);
    N_VConstVectorArray(2, -2.0, w.data());
    // Z[j][i] = a[j] X[i] + Y[j][i], Z = Y; then Z[i] = sum_j c[j] X[j][i], Z = X[0].
    N_Vector* yy[2] = {y.data(), z.data()};
    N_VScaleAddMultiVectorArray(kArray, 2, c, x.data(), yy, yy);
    N_Vector* xx[3] = {x.data(), y.data(), z.data()};
    N_VLinearCombinationVectorArray(kArray, 3, c, xx, x.data());
    N_VLinearCombinationVectorArray(kArray, 3, c, xx, w.data());
  }
  ExpectSlotsEqual("vector arrays");
  std::vector<double> norms[2] = {std::vector<double>(kArray), std::vector<double>(kArray)};
  for (int kind = 0; kind < 2; ++kind) {
    std::vector<N_Vector> x = Array(kind, 0), w = Array(kind, kArray);
    N_VWrmsNormVectorArray(kArray, x.data(), w.data(), norms[kind].data());
  }
  for (int k = 0; k < kArray; ++k) EXPECT_DOUBLE_EQ(norms[1][k], norms[0][k]) << k;
}

// A x = b for random diagonally dominated matrices (pivoting still happens:
// the dominant entry is put off the diagonal), on the substitution path and,
// after more than n solves with one factorisation, on the explicit inverse.
TEST_P(KernelsTest, DenseSolverMatchesSundials) {
  MatrixPtr a_ours(SUNDenseMatrix(n_, n_, context_.get()));
  MatrixPtr a_theirs(SUNDenseMatrix(n_, n_, context_.get()));
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) {
      const double value = Random() - 1.0 + (i == (j + 1) % n_ ? 4.0 * n_ : 0.0);
      SM_ELEMENT_D(a_ours.get(), i, j) = value;
      SM_ELEMENT_D(a_theirs.get(), i, j) = value;
    }
  }
  InstallFastMatrixKernels(a_ours.get());
  LinearSolverPtr ours(NewFastDenseSolver(n_, context_.get()));
  LinearSolverPtr theirs(SUNLinSol_Dense(reference_.get(), a_theirs.get(), context_.get()));
  ASSERT_NE(ours, nullptr);
  ASSERT_EQ(SUNLinSolInitialize(ours.get()), 0);
  ASSERT_EQ(SUNLinSolInitialize(theirs.get()), 0);
  ASSERT_EQ(SUNLinSolSetup(ours.get(), a_ours.get()), 0);
  ASSERT_EQ(SUNLinSolSetup(theirs.get(), a_theirs.get()), 0);
  for (int solve = 0; solve < 2 * n_ + 2; ++solve) {
    for (int i = 0; i < n_; ++i) NV_Ith_S(V(0, 1), i) = NV_Ith_S(V(1, 1), i) = Random();
    ASSERT_EQ(SUNLinSolSolve(theirs.get(), a_theirs.get(), V(0, 0), V(0, 1), 0.0), 0);
    ASSERT_EQ(SUNLinSolSolve(ours.get(), a_ours.get(), V(1, 1), V(1, 1), 0.0), 0);  // x = b
    for (int i = 0; i < n_; ++i) {
      EXPECT_NEAR(NV_Ith_S(V(1, 1), i), NV_Ith_S(V(0, 0), i), 1e-13)
          << "n = " << n_ << ", solve " << solve << ", element " << i;
    }
  }
}

TEST_P(KernelsTest, SingularMatrixIsARecoverableFailure) {
  MatrixPtr a(SUNDenseMatrix(n_, n_, context_.get()));
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i < n_; ++i) SM_ELEMENT_D(a.get(), i, j) = j == n_ - 1 ? 0.0 : Random();
  }
  LinearSolverPtr ours(NewFastDenseSolver(n_, context_.get()));
  EXPECT_EQ(SUNLinSolSetup(ours.get(), a.get()), SUNLS_LUFACT_FAIL);
  EXPECT_EQ(SUNLinSolLastFlag(ours.get()), n_);
}

// 4..12: the compiled sizes; 5, 14 and 17: the run-time-length path.
INSTANTIATE_TEST_SUITE_P(StateCounts, KernelsTest, ::testing::Values(4, 5, 6, 8, 10, 12, 14, 17));

}  // namespace
}  // namespace pneumaid::internal
