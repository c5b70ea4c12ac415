#include "fast_kernels.h"

#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace pneumaid::internal {
namespace {

// Largest system the dense solver takes (the actuator has at most 12 states).
constexpr sunindextype kMaxDenseSize = 32;

inline double* Data(N_Vector v) { return NV_DATA_S(v); }

// The kernels are templates on the vector length: N > 0 is a length known at
// compile time (the actuator's layouts, 4 to 12 states), which the compiler
// unrolls without the aliasing checks and remainder loops that a run-time
// length needs (the LU solve on 8 states: half the instructions). N = 0
// reads the length from the object.
template <int N>
constexpr sunindextype FixedOr(sunindextype run_time_length) {
  return N > 0 ? N : run_time_length;
}

template <int N>
inline sunindextype Length(N_Vector v) {
  return FixedOr<N>(NV_LENGTH_S(v));
}

template <int N>
struct VectorKernels {
  static void LinearSum(double a, N_Vector x, double b, N_Vector y, N_Vector z) {
    const double *xd = Data(x), *yd = Data(y);
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
  }

  static void Const(double c, N_Vector z) {
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = c;
  }

  static void Scale(double c, N_Vector x, N_Vector z) {
    const double* xd = Data(x);
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = c * xd[i];
  }

  static void Prod(N_Vector x, N_Vector y, N_Vector z) {
    const double *xd = Data(x), *yd = Data(y);
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = xd[i] * yd[i];
  }

  static void Div(N_Vector x, N_Vector y, N_Vector z) {
    const double *xd = Data(x), *yd = Data(y);
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = xd[i] / yd[i];
  }

  static void Abs(N_Vector x, N_Vector z) {
    const double* xd = Data(x);
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = std::fabs(xd[i]);
  }

  static void Inv(N_Vector x, N_Vector z) {
    const double* xd = Data(x);
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = 1.0 / xd[i];
  }

  static void AddConst(N_Vector x, double b, N_Vector z) {
    const double* xd = Data(x);
    double* zd = Data(z);
    for (sunindextype i = 0, n = Length<N>(z); i < n; ++i) zd[i] = xd[i] + b;
  }

  static double WSqrSumLocal(N_Vector x, N_Vector w) {
    const double *xd = Data(x), *wd = Data(w);
    double sum = 0;
    for (sunindextype i = 0, n = Length<N>(x); i < n; ++i) sum += (xd[i] * wd[i]) * (xd[i] * wd[i]);
    return sum;
  }

  static double WrmsNorm(N_Vector x, N_Vector w) {
    return std::sqrt(WSqrSumLocal(x, w) / static_cast<double>(Length<N>(x)));
  }

  static double MaxNorm(N_Vector x) {
    const double* xd = Data(x);
    double max = 0;
    for (sunindextype i = 0, n = Length<N>(x); i < n; ++i) max = std::fmax(max, std::fabs(xd[i]));
    return max;
  }

  // z = sum_k c[k] x_k with x_k = Data(vector(k)); z may alias x_0. With N
  // fixed the sum is kept in registers (CVodeGetDky calls this at every output).
  template <typename Vector>
  static void Combine(int count, const double* c, Vector vector, N_Vector z) {
    double* zd = Data(z);
    const double* x0 = Data(vector(0));
    if constexpr (N > 0) {
      double sum[N];
      for (int i = 0; i < N; ++i) sum[i] = c[0] * x0[i];
      for (int k = 1; k < count; ++k) {
        const double* xk = Data(vector(k));
        for (int i = 0; i < N; ++i) sum[i] += c[k] * xk[i];
      }
      for (int i = 0; i < N; ++i) zd[i] = sum[i];
    } else {
      const sunindextype n = Length<N>(z);
      for (sunindextype i = 0; i < n; ++i) zd[i] = c[0] * x0[i];
      for (int k = 1; k < count; ++k) {
        const double* xk = Data(vector(k));
        for (sunindextype i = 0; i < n; ++i) zd[i] += c[k] * xk[i];
      }
    }
  }

  static int LinearCombination(int count, double* c, N_Vector* x, N_Vector z) {
    Combine(
        count, c, [x](int k) { return x[k]; }, z);
    return 0;
  }

  static int ScaleAddMulti(int count, double* a, N_Vector x, N_Vector* y, N_Vector* z) {
    const double* xd = Data(x);
    const sunindextype n = Length<N>(x);
    for (int k = 0; k < count; ++k) {
      const double* yd = Data(y[k]);
      double* zd = Data(z[k]);
      for (sunindextype i = 0; i < n; ++i) zd[i] = a[k] * xd[i] + yd[i];
    }
    return 0;
  }

  // The vector-array operations of CVODES' sensitivities, one vector of the
  // array at a time (same results as SUNDIALS' own; element by element, so
  // an output may alias an input of the same index).

  // y += a x
  static void Axpy(double a, N_Vector x, N_Vector y) {
    const double* xd = Data(x);
    double* yd = Data(y);
    for (sunindextype i = 0, n = Length<N>(y); i < n; ++i) yd[i] += a * xd[i];
  }

  // Z[i] = a X[i] + b Y[i]; CVODES mostly asks for Y[i] += a X[i], one load
  // and multiplication less per element.
  static int LinearSumVectorArray(int count, double a, N_Vector* x, double b, N_Vector* y,
                                  N_Vector* z) {
    if (b == 1.0 && z == y) {
      for (int i = 0; i < count; ++i) Axpy(a, x[i], y[i]);
    } else if (a == 1.0 && z == x) {
      for (int i = 0; i < count; ++i) Axpy(b, y[i], x[i]);
    } else {
      for (int i = 0; i < count; ++i) LinearSum(a, x[i], b, y[i], z[i]);
    }
    return 0;
  }

  // Z[i] = c[i] X[i]
  static int ScaleVectorArray(int count, double* c, N_Vector* x, N_Vector* z) {
    for (int i = 0; i < count; ++i) Scale(c[i], x[i], z[i]);
    return 0;
  }

  static int ConstVectorArray(int count, double c, N_Vector* z) {
    for (int i = 0; i < count; ++i) Const(c, z[i]);
    return 0;
  }

  static int WrmsNormVectorArray(int count, N_Vector* x, N_Vector* w, double* norms) {
    for (int i = 0; i < count; ++i) norms[i] = WrmsNorm(x[i], w[i]);
    return 0;
  }

  // Z[j][i] = a[j] X[i] + Y[j][i]
  static int ScaleAddMultiVectorArray(int count, int sums, double* a, N_Vector* x, N_Vector** y,
                                      N_Vector** z) {
    for (int i = 0; i < count; ++i) {
      const double* xd = Data(x[i]);
      const sunindextype n = Length<N>(x[i]);
      for (int j = 0; j < sums; ++j) {
        const double* yd = Data(y[j][i]);
        double* zd = Data(z[j][i]);
        for (sunindextype k = 0; k < n; ++k) zd[k] = a[j] * xd[k] + yd[k];
      }
    }
    return 0;
  }

  // Z[i] = sum_j c[j] X[j][i]
  static int LinearCombinationVectorArray(int count, int sums, double* c, N_Vector** x,
                                          N_Vector* z) {
    for (int i = 0; i < count; ++i)
      Combine(
          sums, c, [x, i](int j) { return x[j][i]; }, z[i]);
    return 0;
  }

  static void Install(N_Vector_Ops ops) {
    ops->nvlinearsum = LinearSum;
    ops->nvconst = Const;
    ops->nvscale = Scale;
    ops->nvprod = Prod;
    ops->nvdiv = Div;
    ops->nvabs = Abs;
    ops->nvinv = Inv;
    ops->nvaddconst = AddConst;
    ops->nvwrmsnorm = WrmsNorm;
    ops->nvwsqrsumlocal = WSqrSumLocal;
    ops->nvmaxnorm = MaxNorm;
    ops->nvlinearcombination = LinearCombination;
    ops->nvscaleaddmulti = ScaleAddMulti;
    ops->nvlinearsumvectorarray = LinearSumVectorArray;
    ops->nvscalevectorarray = ScaleVectorArray;
    ops->nvconstvectorarray = ConstVectorArray;
    ops->nvwrmsnormvectorarray = WrmsNormVectorArray;
    ops->nvscaleaddmultivectorarray = ScaleAddMultiVectorArray;
    ops->nvlinearcombinationvectorarray = LinearCombinationVectorArray;
  }
};

int MatrixCopy(SUNMatrix from, SUNMatrix to) {
  const double* a = SM_DATA_D(from);
  double* b = SM_DATA_D(to);
  for (sunindextype i = 0, n = SM_LDATA_D(from); i < n; ++i) b[i] = a[i];
  return 0;
}

// A = c A + I
int MatrixScaleAddIdentity(double c, SUNMatrix matrix) {
  double* a = SM_DATA_D(matrix);
  const sunindextype rows = SM_ROWS_D(matrix), cols = SM_COLUMNS_D(matrix);
  for (sunindextype i = 0, n = rows * cols; i < n; ++i) a[i] *= c;
  for (sunindextype j = 0; j < cols && j < rows; ++j) a[j * rows + j] += 1.0;
  return 0;
}

// Dense LU with partial pivoting, column-major like SUNDIALS' dense matrix,
// and, once a factorisation is reused often, the explicit inverse formed from
// it. With sensitivities the staggered corrector solves with one Newton
// matrix dozens of times (once per sensitivity and iteration), and for these
// 4..12 states a row-major matrix-vector product is several times cheaper
// than forward and back substitution; a plain run solves only two or three
// times per factorisation, where forming the inverse (n substitutions) would
// cost more than it saves.
struct DenseLu {
  // Row i of P A is row permutation[i] of A (the row swaps of the
  // factorisation composed, as LAPACK's getrs would apply them one by one).
  std::vector<sunindextype> permutation;
  std::vector<double> inverse;  // row-major n x n, valid when inverse_formed
  bool inverse_formed = false;
  sunindextype solves_since_setup = 0;
  sunindextype last_flag = 0;
};

DenseLu* Content(SUNLinearSolver solver) { return static_cast<DenseLu*>(solver->content); }

SUNLinearSolver_Type GetType(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID GetId(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int Initialize(SUNLinearSolver solver) {
  Content(solver)->last_flag = 0;
  return SUNLS_SUCCESS;
}

template <int N>
inline sunindextype Rows(SUNMatrix matrix) {
  return FixedOr<N>(SM_ROWS_D(matrix));
}

// Setup and solve for n x n matrices, n = N when N > 0 (see VectorKernels).
template <int N>
struct DenseKernels {
  // x = A^-1 b with the LU factors of A.
  static void SolveWithFactors(const DenseLu& lu, const double* a, sunindextype n, double* x) {
    // On a local copy, which the compiler keeps in registers when N is fixed
    // (x could alias the factors, so it would store and reload every update);
    // the row permutation is gathered into it.
    n = FixedOr<N>(n);
    double local[N > 0 ? N : kMaxDenseSize];
    for (sunindextype i = 0; i < n; ++i) local[i] = x[lu.permutation[i]];
    Substitute(a, n, local);
    for (sunindextype i = 0; i < n; ++i) x[i] = local[i];
  }

  // The triangular solves L y = P b, U x = y on P b.
  static void Substitute(const double* a, sunindextype n, double* x) {
    n = FixedOr<N>(n);
#pragma GCC unroll 16
    for (sunindextype k = 0; k < n; ++k) {  // forward
      const double* col_k = a + k * n;
#pragma GCC unroll 16
      for (sunindextype i = k + 1; i < n; ++i) x[i] -= col_k[i] * x[k];
    }
#pragma GCC unroll 16
    for (sunindextype k = n - 1; k >= 0; --k) {  // backward
      const double* col_k = a + k * n;
      x[k] /= col_k[k];
#pragma GCC unroll 16
      for (sunindextype i = 0; i < k; ++i) x[i] -= col_k[i] * x[k];
    }
  }

  // Column j of the inverse is A^-1 e_j; stored transposed (row-major).
  static void FormInverse(DenseLu* lu, const double* a, sunindextype n) {
    double column[kMaxDenseSize];
    for (sunindextype j = 0; j < n; ++j) {
      std::fill(column, column + n, 0.0);
      column[j] = 1.0;
      SolveWithFactors(*lu, a, n, column);
      for (sunindextype i = 0; i < n; ++i) lu->inverse[i * n + j] = column[i];
    }
  }

  static int Setup(SUNLinearSolver solver, SUNMatrix matrix) {
    DenseLu* lu = Content(solver);
    const sunindextype n = Rows<N>(matrix);
    double* a = SM_DATA_D(matrix);
    for (sunindextype i = 0; i < n; ++i) lu->permutation[i] = i;
    for (sunindextype k = 0; k < n; ++k) {
      double* col_k = a + k * n;
      sunindextype pivot = k;
      for (sunindextype i = k + 1; i < n; ++i) {
        if (std::fabs(col_k[i]) > std::fabs(col_k[pivot])) pivot = i;
      }
      if (col_k[pivot] == 0.0) {
        lu->last_flag = k + 1;
        return SUNLS_LUFACT_FAIL;  // recoverable: CVODE retries with a smaller step
      }
      if (pivot != k) {
        for (sunindextype j = 0; j < n; ++j) std::swap(a[j * n + k], a[j * n + pivot]);
        std::swap(lu->permutation[k], lu->permutation[pivot]);
      }
      const double inverse = 1.0 / col_k[k];
#pragma GCC unroll 16
      for (sunindextype i = k + 1; i < n; ++i) col_k[i] *= inverse;
      for (sunindextype j = k + 1; j < n; ++j) {
        double* col_j = a + j * n;
        const double factor = col_j[k];
        if (factor == 0.0) continue;
#pragma GCC unroll 16
        for (sunindextype i = k + 1; i < n; ++i) col_j[i] -= factor * col_k[i];
      }
    }
    lu->inverse_formed = false;
    lu->solves_since_setup = 0;
    lu->last_flag = 0;
    return SUNLS_SUCCESS;
  }

  // result = inverse b for the row-major inverse.
  static void Multiply(const double* inverse, sunindextype n, const double* b, double* result) {
    n = FixedOr<N>(n);
    for (sunindextype i = 0; i < n; ++i) {
      double sum = 0.0;
      for (sunindextype j = 0; j < n; ++j) sum += inverse[i * n + j] * b[j];
      result[i] = sum;
    }
  }

  static int Solve(SUNLinearSolver solver, SUNMatrix matrix, N_Vector x, N_Vector b, double) {
    DenseLu* lu = Content(solver);
    const sunindextype n = Rows<N>(matrix);
    const double* a = SM_DATA_D(matrix);
    // The inverse pays for itself after about n solves with one factorisation.
    if (!lu->inverse_formed && ++lu->solves_since_setup > n) {
      FormInverse(lu, a, n);
      lu->inverse_formed = true;
    }
    double* xd = Data(x);
    if (lu->inverse_formed) {
      double result[kMaxDenseSize];
      Multiply(lu->inverse.data(), n, Data(b), result);
      for (sunindextype i = 0; i < n; ++i) xd[i] = result[i];  // x may alias b
    } else {
      const double* bd = Data(b);
      if (xd != bd) {
        for (sunindextype i = 0; i < n; ++i) xd[i] = bd[i];
      }
      SolveWithFactors(*lu, a, n, xd);
    }
    lu->last_flag = 0;
    return SUNLS_SUCCESS;
  }

  static void Install(SUNLinearSolver solver) {
    solver->ops->setup = Setup;
    solver->ops->solve = Solve;
  }
};

// Calls Kernels<n>::Install(target) for the actuator's layouts (4 states plus
// optional groups of 2 states: every even size from 4 to 12), Kernels<0>
// otherwise.
template <template <int> class Kernels, typename Target>
void InstallForLength(sunindextype n, Target target) {
  switch (n) {
    case 4:
      return Kernels<4>::Install(target);
    case 6:
      return Kernels<6>::Install(target);
    case 8:
      return Kernels<8>::Install(target);
    case 10:
      return Kernels<10>::Install(target);
    case 12:
      return Kernels<12>::Install(target);
    default:
      return Kernels<0>::Install(target);
  }
}

sunindextype LastFlag(SUNLinearSolver solver) { return Content(solver)->last_flag; }

int Free(SUNLinearSolver solver) {
  if (solver == nullptr) return SUNLS_SUCCESS;
  delete Content(solver);
  solver->content = nullptr;
  SUNLinSolFreeEmpty(solver);
  return SUNLS_SUCCESS;
}

}  // namespace

void InstallFastVectorKernels(N_Vector vector) {
  InstallForLength<VectorKernels>(NV_LENGTH_S(vector), vector->ops);
}

void InstallFastMatrixKernels(SUNMatrix matrix) {
  matrix->ops->copy = MatrixCopy;
  matrix->ops->scaleaddi = MatrixScaleAddIdentity;
}

SUNLinearSolver NewFastDenseSolver(sunindextype n, SUNContext context) {
  SUNLinearSolver solver = SUNLinSolNewEmpty(context);
  if (solver == nullptr) return nullptr;
  solver->ops->gettype = GetType;
  solver->ops->getid = GetId;
  solver->ops->initialize = Initialize;
  InstallForLength<DenseKernels>(n, solver);
  solver->ops->lastflag = LastFlag;
  solver->ops->free = Free;
  if (n > kMaxDenseSize) {
    SUNLinSolFreeEmpty(solver);
    return nullptr;
  }
  auto* content = new DenseLu;
  content->permutation.assign(static_cast<size_t>(n), 0);
  content->inverse.assign(static_cast<size_t>(n * n), 0.0);
  solver->content = content;
  return solver;
}

}  // namespace pneumaid::internal
