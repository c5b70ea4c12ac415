#include "fast_kernels.h"

#include <sunmatrix/sunmatrix_dense.h>

#include <cmath>
#include <vector>

namespace pneumaid::internal {
namespace {

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

// Dense LU with partial pivoting, column-major like SUNDIALS' dense matrix.
struct DenseLu {
  std::vector<sunindextype> pivots;
  sunindextype last_flag = 0;
};

DenseLu* Content(SUNLinearSolver solver) { return static_cast<DenseLu*>(solver->content); }

SUNLinearSolver_Type GetType(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID GetId(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int Initialize(SUNLinearSolver solver) {
  Content(solver)->last_flag = 0;
  return SUNLS_SUCCESS;
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
  lu->last_flag = 0;
  return SUNLS_SUCCESS;
}

int Solve(SUNLinearSolver solver, SUNMatrix matrix, N_Vector x, N_Vector b, double) {
  const DenseLu* lu = Content(solver);
  const sunindextype n = SM_ROWS_D(matrix);
  const double* a = SM_DATA_D(matrix);
  double* xd = Data(x);
  const double* bd = Data(b);
  for (sunindextype i = 0; i < n; ++i) xd[i] = bd[i];
  // The row swaps of the factorisation moved whole rows of L, so apply them
  // all before the forward substitution (as LAPACK's getrs does).
  for (sunindextype k = 0; k < n; ++k) {
    const sunindextype pivot = lu->pivots[k];
    if (pivot != k) std::swap(xd[k], xd[pivot]);
  }
  for (sunindextype k = 0; k < n; ++k) {  // forward: L y = P b
    const double* col_k = a + k * n;
    for (sunindextype i = k + 1; i < n; ++i) xd[i] -= col_k[i] * xd[k];
  }
  for (sunindextype k = n - 1; k >= 0; --k) {  // backward: U x = y
    const double* col_k = a + k * n;
    xd[k] /= col_k[k];
    for (sunindextype i = 0; i < k; ++i) xd[i] -= col_k[i] * xd[k];
  }
  Content(solver)->last_flag = 0;
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
  auto* content = new DenseLu;
  content->pivots.assign(static_cast<size_t>(n), 0);
  solver->content = content;
  return solver;
}

}  // namespace pneumaid::internal
