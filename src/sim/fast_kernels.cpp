#include "fast_kernels.h"

#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace pneumaid::internal {
namespace {

// Largest system the dense solver takes (the actuator has at most 14 states).
constexpr sunindextype kMaxDenseSize = 32;

inline double* Data(N_Vector v) { return NV_DATA_S(v); }
inline sunindextype Length(N_Vector v) { return NV_LENGTH_S(v); }

void LinearSum(double a, N_Vector x, double b, N_Vector y, N_Vector z) {
  const double *xd = Data(x), *yd = Data(y);
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = a * xd[i] + b * yd[i];
}

void Const(double c, N_Vector z) {
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = c;
}

void Scale(double c, N_Vector x, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = c * xd[i];
}

void Prod(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = Data(x), *yd = Data(y);
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = xd[i] * yd[i];
}

void Div(N_Vector x, N_Vector y, N_Vector z) {
  const double *xd = Data(x), *yd = Data(y);
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = xd[i] / yd[i];
}

void Abs(N_Vector x, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = std::fabs(xd[i]);
}

void Inv(N_Vector x, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = 1.0 / xd[i];
}

void AddConst(N_Vector x, double b, N_Vector z) {
  const double* xd = Data(x);
  double* zd = Data(z);
  for (sunindextype i = 0, n = Length(z); i < n; ++i) zd[i] = xd[i] + b;
}

double WSqrSumLocal(N_Vector x, N_Vector w) {
  const double *xd = Data(x), *wd = Data(w);
  double sum = 0;
  for (sunindextype i = 0, n = Length(x); i < n; ++i) sum += (xd[i] * wd[i]) * (xd[i] * wd[i]);
  return sum;
}

double WrmsNorm(N_Vector x, N_Vector w) {
  return std::sqrt(WSqrSumLocal(x, w) / static_cast<double>(Length(x)));
}

double MaxNorm(N_Vector x) {
  const double* xd = Data(x);
  double max = 0;
  for (sunindextype i = 0, n = Length(x); i < n; ++i) max = std::fmax(max, std::fabs(xd[i]));
  return max;
}

int LinearCombination(int count, double* c, N_Vector* x, N_Vector z) {
  double* zd = Data(z);
  const sunindextype n = Length(z);
  // z may alias x[0]; scale it in place first, then accumulate the rest.
  const double* x0 = Data(x[0]);
  for (sunindextype i = 0; i < n; ++i) zd[i] = c[0] * x0[i];
  for (int k = 1; k < count; ++k) {
    const double* xk = Data(x[k]);
    for (sunindextype i = 0; i < n; ++i) zd[i] += c[k] * xk[i];
  }
  return 0;
}

int ScaleAddMulti(int count, double* a, N_Vector x, N_Vector* y, N_Vector* z) {
  const double* xd = Data(x);
  const sunindextype n = Length(x);
  for (int k = 0; k < count; ++k) {
    const double* yd = Data(y[k]);
    double* zd = Data(z[k]);
    for (sunindextype i = 0; i < n; ++i) zd[i] = a[k] * xd[i] + yd[i];
  }
  return 0;
}

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
// 4..14 states a row-major matrix-vector product is several times cheaper
// than forward and back substitution; a plain run solves only two or three
// times per factorisation, where forming the inverse (n substitutions) would
// cost more than it saves.
struct DenseLu {
  std::vector<sunindextype> pivots;
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

// x = A^-1 b with the LU factors of A (pivots applied first, as LAPACK's
// getrs does: the row swaps of the factorisation moved whole rows of L).
void SolveWithFactors(const DenseLu& lu, const double* a, sunindextype n, double* x) {
  for (sunindextype k = 0; k < n; ++k) {
    const sunindextype pivot = lu.pivots[k];
    if (pivot != k) std::swap(x[k], x[pivot]);
  }
  for (sunindextype k = 0; k < n; ++k) {  // forward: L y = P b
    const double* col_k = a + k * n;
    for (sunindextype i = k + 1; i < n; ++i) x[i] -= col_k[i] * x[k];
  }
  for (sunindextype k = n - 1; k >= 0; --k) {  // backward: U x = y
    const double* col_k = a + k * n;
    x[k] /= col_k[k];
    for (sunindextype i = 0; i < k; ++i) x[i] -= col_k[i] * x[k];
  }
}

// Column j of the inverse is A^-1 e_j; stored transposed (row-major).
void FormInverse(DenseLu* lu, const double* a, sunindextype n) {
  std::vector<double> column(static_cast<size_t>(n));
  for (sunindextype j = 0; j < n; ++j) {
    std::fill(column.begin(), column.end(), 0.0);
    column[j] = 1.0;
    SolveWithFactors(*lu, a, n, column.data());
    for (sunindextype i = 0; i < n; ++i) lu->inverse[i * n + j] = column[i];
  }
}

int Setup(SUNLinearSolver solver, SUNMatrix matrix) {
  DenseLu* lu = Content(solver);
  const sunindextype n = SM_ROWS_D(matrix);
  double* a = SM_DATA_D(matrix);
  for (sunindextype k = 0; k < n; ++k) {
    double* col_k = a + k * n;
    sunindextype pivot = k;
    for (sunindextype i = k + 1; i < n; ++i) {
      if (std::fabs(col_k[i]) > std::fabs(col_k[pivot])) pivot = i;
    }
    lu->pivots[k] = pivot;
    if (col_k[pivot] == 0.0) {
      lu->last_flag = k + 1;
      return SUNLS_LUFACT_FAIL;  // recoverable: CVODE retries with a smaller step
    }
    if (pivot != k) {
      for (sunindextype j = 0; j < n; ++j) std::swap(a[j * n + k], a[j * n + pivot]);
    }
    const double inverse = 1.0 / col_k[k];
    for (sunindextype i = k + 1; i < n; ++i) col_k[i] *= inverse;
    for (sunindextype j = k + 1; j < n; ++j) {
      double* col_j = a + j * n;
      const double factor = col_j[k];
      if (factor == 0.0) continue;
      for (sunindextype i = k + 1; i < n; ++i) col_j[i] -= factor * col_k[i];
    }
  }
  lu->inverse_formed = false;
  lu->solves_since_setup = 0;
  lu->last_flag = 0;
  return SUNLS_SUCCESS;
}

// result = inverse b for an n x n row-major inverse; fixed sizes unroll.
template <int N>
void MultiplyFixed(const double* inverse, const double* b, double* result) {
  for (int i = 0; i < N; ++i) {
    double sum = 0.0;
    for (int j = 0; j < N; ++j) sum += inverse[i * N + j] * b[j];
    result[i] = sum;
  }
}

void Multiply(const double* inverse, sunindextype n, const double* b, double* result) {
  switch (n) {  // the actuator's layouts: 4 states plus optional groups
    case 4:
      return MultiplyFixed<4>(inverse, b, result);
    case 6:
      return MultiplyFixed<6>(inverse, b, result);
    case 8:
      return MultiplyFixed<8>(inverse, b, result);
    case 10:
      return MultiplyFixed<10>(inverse, b, result);
    case 12:
      return MultiplyFixed<12>(inverse, b, result);
    default:
      for (sunindextype i = 0; i < n; ++i) {
        double sum = 0.0;
        for (sunindextype j = 0; j < n; ++j) sum += inverse[i * n + j] * b[j];
        result[i] = sum;
      }
  }
}

int Solve(SUNLinearSolver solver, SUNMatrix matrix, N_Vector x, N_Vector b, double) {
  DenseLu* lu = Content(solver);
  const sunindextype n = SM_ROWS_D(matrix);
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
  N_Vector_Ops ops = vector->ops;
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
  solver->ops->setup = Setup;
  solver->ops->solve = Solve;
  solver->ops->lastflag = LastFlag;
  solver->ops->free = Free;
  if (n > kMaxDenseSize) {
    SUNLinSolFreeEmpty(solver);
    return nullptr;
  }
  auto* content = new DenseLu;
  content->pivots.assign(static_cast<size_t>(n), 0);
  content->inverse.assign(static_cast<size_t>(n * n), 0.0);
  solver->content = content;
  return solver;
}

}  // namespace pneumaid::internal
