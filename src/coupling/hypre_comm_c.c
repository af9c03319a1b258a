/* The few hypre calls Fortran cannot make directly.
 *
 * 1. Calls that take an MPI communicator: Fortran holds an integer handle (MPI_Fint), hypre's C
 *    API wants an MPI_Comm; passing the integer straight through aborts with MPI_ERR_COMM. Each
 *    wrapper converts with MPI_Comm_f2c and forwards every other argument unchanged.
 * 2. The local part of a HYPRE_ParVector: hypre has HYPRE_ParVectorGetValues but no public
 *    "set values" for a ParCSR vector, and a user preconditioner must write its correction into
 *    the ParVector hypre hands it. The local part of a ParVector is one contiguous array of this
 *    rank's rows (hypre reference manual, ParCSR vectors; hypre_ParVectorLocalVector and
 *    hypre_VectorData in _hypre_parcsr_mv.h, the accessors hypre's own solvers use), so we return
 *    a pointer to it and its length: no copies, the same layout as the rank's block of rows.
 * 3. A ParCSR matrix built straight from the rows, and new values written into it (below).
 */
#include <mpi.h>
#include "HYPRE.h"
#include "HYPRE_IJ_mv.h"
#include "HYPRE_parcsr_ls.h"
#include "_hypre_parcsr_mv.h"

HYPRE_Int agglo_hypre_ij_vector_create(MPI_Fint comm, HYPRE_BigInt jlower, HYPRE_BigInt jupper,
                                       HYPRE_IJVector *vector)
{
  return HYPRE_IJVectorCreate(MPI_Comm_f2c(comm), jlower, jupper, vector);
}

HYPRE_Int agglo_hypre_bicgstab_create(MPI_Fint comm, HYPRE_Solver *solver)
{
  return HYPRE_ParCSRBiCGSTABCreate(MPI_Comm_f2c(comm), solver);
}

HYPRE_Int agglo_hypre_gmres_create(MPI_Fint comm, HYPRE_Solver *solver)
{
  return HYPRE_ParCSRGMRESCreate(MPI_Comm_f2c(comm), solver);
}

/* Pointer to the first local entry of a ParCSR vector; *size receives the local length. */
HYPRE_Complex *agglo_hypre_par_vector_local_data(HYPRE_ParVector vector, HYPRE_Int *size)
{
  hypre_Vector *local = hypre_ParVectorLocalVector((hypre_ParVector *) vector);
  *size = hypre_VectorSize(local);
  return hypre_VectorData(local);
}

/* 3. A ParCSR matrix straight from this rank's rows in CSR form (the layout of sparse_rows_t:
 *    global rows first_row .. last_row numbered from 1, row_start 1-based with n + 1 entries,
 *    1-based global columns), without the IJ interface. HYPRE_IJMatrixSetValues + Assemble cost
 *    0.1-0.2 s per million rows (hashing and sorting of every entry, docs/studies/performance.md);
 *    the split into hypre's diagonal block (columns this rank owns, local numbers) and
 *    off-diagonal block (other columns, numbered through the sorted col_map_offd) is two linear
 *    passes and one sort of the few off-rank columns. As the IJ assembly does, the diagonal entry
 *    goes first in its row of the diagonal block (hypre's smoothers and ILU expect it there);
 *    otherwise the entries keep the caller's order. Some rows may come from a second, compact CSR
 *    (the immersed boundary's rows over the Helmholtz rows: no merged copy of the whole matrix).
 *    agglo_hypre_parcsr_set_rows writes new values into rows of the same pattern in place (same
 *    order rule). */
#include <stdlib.h>
#include "_hypre_utilities.h"

static int compare_big(const void *a, const void *b)
{
  HYPRE_BigInt x = *(const HYPRE_BigInt *) a, y = *(const HYPRE_BigInt *) b;
  return (x > y) - (x < y);
}

/* Position of column (0-based global) in the sorted col_map, -1 if absent. */
static HYPRE_Int offd_index(const HYPRE_BigInt *map, HYPRE_Int n, HYPRE_BigInt column)
{
  HYPRE_Int low = 0, high = n - 1;
  while (low <= high) {
    HYPRE_Int mid = (low + high) / 2;
    if (map[mid] == column) return mid;
    if (map[mid] < column) low = mid + 1; else high = mid - 1;
  }
  return -1;
}

/* Entries entry_first .. entry_last - 1 (0-based) of columns/values, the whole of local row r
 * (0-based), into the diagonal and off-diagonal blocks at the row's starts (their column numbers
 * too when diag_j and offd_j are given); the diagonal entry swapped to the front of the
 * diagonal block's row. Non-zero if the row does not fit the blocks' row lengths. */
static HYPRE_Int fill_row(HYPRE_Int r, HYPRE_BigInt first0, HYPRE_BigInt last0, HYPRE_Int entry_first,
                          HYPRE_Int entry_last, const HYPRE_BigInt *columns, const HYPRE_Complex *values,
                          const HYPRE_BigInt *map,
                          HYPRE_Int n_map, const HYPRE_Int *diag_i, HYPRE_Int *diag_j, HYPRE_Complex *diag_data,
                          const HYPRE_Int *offd_i, HYPRE_Int *offd_j, HYPRE_Complex *offd_data)
{
  HYPRE_Int d = diag_i[r], o = offd_i[r], e;
  for (e = entry_first; e < entry_last; e++) {
    HYPRE_BigInt column = columns[e] - 1;
    if (column >= first0 && column <= last0) {
      if (d >= diag_i[r + 1]) return 1;
      if (diag_j) diag_j[d] = (HYPRE_Int) (column - first0);
      diag_data[d] = values[e];
      if (column - first0 == r && d != diag_i[r]) {
        HYPRE_Complex value = diag_data[d];
        diag_data[d] = diag_data[diag_i[r]];
        diag_data[diag_i[r]] = value;
        if (diag_j) { diag_j[d] = diag_j[diag_i[r]]; diag_j[diag_i[r]] = r; }
      }
      d++;
    } else {
      if (o >= offd_i[r + 1]) return 1;
      if (offd_j) {
        HYPRE_Int k = offd_index(map, n_map, column);
        if (k < 0) return 1;
        offd_j[o] = k;
      }
      offd_data[o] = values[e];
      o++;
    }
  }
  return (d != diag_i[r + 1] || o != offd_i[r + 1]);
}

/* The rows of the matrix: a base CSR of every local row, some rows replaced by those of a
 * compact CSR (n_over rows, ascending 1-based local numbers in over_rows[], their entries
 * over_start[s] .. over_start[s + 1] - 1, 1-based). row_range gives local row r's (0-based)
 * entry range and arrays; *next is the index of the first replaced row not yet passed. */
typedef struct {
  const HYPRE_Int *start; const HYPRE_BigInt *columns; const HYPRE_Complex *values;
  HYPRE_Int n_over; const HYPRE_Int *over_rows, *over_start; const HYPRE_BigInt *over_columns;
  const HYPRE_Complex *over_values;
} row_source;

static void row_range(const row_source *src, HYPRE_Int r, HYPRE_Int *next, HYPRE_Int *first, HYPRE_Int *last,
                      const HYPRE_BigInt **columns, const HYPRE_Complex **values)
{
  if (*next < src->n_over && src->over_rows[*next] == r + 1) {
    *first = src->over_start[*next] - 1;
    *last = src->over_start[*next + 1] - 1;
    *columns = src->over_columns;
    *values = src->over_values;
    (*next)++;
  } else {
    *first = src->start[r] - 1;
    *last = src->start[r + 1] - 1;
    *columns = src->columns;
    *values = src->values;
  }
}

HYPRE_Int agglo_hypre_parcsr_create(MPI_Fint comm, HYPRE_BigInt first_row, HYPRE_BigInt last_row,
                                    HYPRE_BigInt global_rows, const HYPRE_Int *row_start,
                                    const HYPRE_BigInt *columns, const HYPRE_Complex *values, HYPRE_Int n_over,
                                    const HYPRE_Int *over_rows, const HYPRE_Int *over_start,
                                    const HYPRE_BigInt *over_columns, const HYPRE_Complex *over_values,
                                    HYPRE_ParCSRMatrix *matrix_out)
{
  row_source src = {row_start, columns, values, n_over, over_rows, over_start, over_columns, over_values};
  HYPRE_BigInt first0 = first_row - 1, last0 = last_row - 1, starts[2];
  HYPRE_Int n = (HYPRE_Int) (last_row - first_row + 1), r, e, nnz_diag = 0, nnz_offd = 0, n_map = 0, k, next;
  HYPRE_Int first, last;
  const HYPRE_BigInt *cols;
  const HYPRE_Complex *vals;
  HYPRE_BigInt *off = NULL;
  hypre_ParCSRMatrix *A;
  hypre_CSRMatrix *diag, *offd;
  HYPRE_Int *diag_i, *offd_i;

  /* Row lengths of both blocks, and the off-rank columns. */
  diag_i = (HYPRE_Int *) malloc(sizeof(HYPRE_Int) * (n + 1));
  offd_i = (HYPRE_Int *) malloc(sizeof(HYPRE_Int) * (n + 1));
  if (!diag_i || !offd_i) { free(diag_i); free(offd_i); return 1; }
  diag_i[0] = 0;
  offd_i[0] = 0;
  for (r = 0, next = 0; r < n; r++) {
    row_range(&src, r, &next, &first, &last, &cols, &vals);
    for (e = first; e < last; e++) {
      HYPRE_BigInt column = cols[e] - 1;
      if (column >= first0 && column <= last0) nnz_diag++; else nnz_offd++;
    }
    diag_i[r + 1] = nnz_diag;
    offd_i[r + 1] = nnz_offd;
  }
  if (nnz_offd > 0) {
    off = (HYPRE_BigInt *) malloc(sizeof(HYPRE_BigInt) * nnz_offd);
    if (!off) { free(diag_i); free(offd_i); return 1; }
    k = 0;
    for (r = 0, next = 0; r < n; r++) {
      row_range(&src, r, &next, &first, &last, &cols, &vals);
      for (e = first; e < last; e++) {
        HYPRE_BigInt column = cols[e] - 1;
        if (!(column >= first0 && column <= last0)) off[k++] = column;
      }
    }
    qsort(off, nnz_offd, sizeof(HYPRE_BigInt), compare_big);
    for (k = 0; k < nnz_offd; k++)
      if (k == 0 || off[k] != off[n_map - 1]) off[n_map++] = off[k];
  }
  starts[0] = first0;
  starts[1] = last0 + 1;
  A = hypre_ParCSRMatrixCreate(MPI_Comm_f2c(comm), global_rows, global_rows, starts, starts, n_map, nnz_diag,
                               nnz_offd);
  hypre_ParCSRMatrixInitialize(A);
  diag = hypre_ParCSRMatrixDiag(A);
  offd = hypre_ParCSRMatrixOffd(A);
  if (n_map > 0) {
    if (!hypre_ParCSRMatrixColMapOffd(A))
      hypre_ParCSRMatrixColMapOffd(A) = hypre_CTAlloc(HYPRE_BigInt, n_map, HYPRE_MEMORY_HOST);
    for (k = 0; k < n_map; k++) hypre_ParCSRMatrixColMapOffd(A)[k] = off[k];
  }
  for (r = 0; r <= n; r++) {
    hypre_CSRMatrixI(diag)[r] = diag_i[r];
    hypre_CSRMatrixI(offd)[r] = offd_i[r];
  }
  free(diag_i);
  free(offd_i);
  for (r = 0, next = 0; r < n; r++) {
    row_range(&src, r, &next, &first, &last, &cols, &vals);
    if (fill_row(r, first0, last0, first, last, cols, vals, off, n_map, hypre_CSRMatrixI(diag),
                 hypre_CSRMatrixJ(diag), hypre_CSRMatrixData(diag), hypre_CSRMatrixI(offd), hypre_CSRMatrixJ(offd),
                 hypre_CSRMatrixData(offd))) {
      free(off);
      hypre_ParCSRMatrixDestroy(A);
      return 1;
    }
  }
  free(off);
  hypre_ParCSRMatrixSetNumNonzeros(A);
  hypre_MatvecCommPkgCreate(A);
  *matrix_out = (HYPRE_ParCSRMatrix) A;
  return hypre_error_flag;
}

/* New values of n_set local rows (1-based numbers in rows[]) in compact CSR form: the entries of
 * the s-th listed row are row_start[s] .. row_start[s + 1] - 1 (1-based), with the pattern the
 * matrix was created with; non-zero if a row's pattern differs. */
HYPRE_Int agglo_hypre_parcsr_set_rows(HYPRE_ParCSRMatrix matrix, HYPRE_Int n_set, const HYPRE_Int *rows,
                                      const HYPRE_Int *row_start, const HYPRE_BigInt *columns,
                                      const HYPRE_Complex *values)
{
  hypre_ParCSRMatrix *A = (hypre_ParCSRMatrix *) matrix;
  hypre_CSRMatrix *diag = hypre_ParCSRMatrixDiag(A), *offd = hypre_ParCSRMatrixOffd(A);
  HYPRE_BigInt first0 = hypre_ParCSRMatrixFirstRowIndex(A);
  HYPRE_BigInt last0 = first0 + hypre_CSRMatrixNumRows(diag) - 1;
  HYPRE_Int s;
  for (s = 0; s < n_set; s++) {
    HYPRE_Int r = rows[s] - 1;
    if (r < 0 || r >= hypre_CSRMatrixNumRows(diag)) return 1;
    if (fill_row(r, first0, last0, row_start[s] - 1, row_start[s + 1] - 1, columns, values, NULL, 0,
                 hypre_CSRMatrixI(diag), NULL,
                 hypre_CSRMatrixData(diag), hypre_CSRMatrixI(offd), NULL, hypre_CSRMatrixData(offd)))
      return 1;
  }
  return 0;
}
