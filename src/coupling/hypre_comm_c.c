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
 */
#include <mpi.h>
#include "HYPRE.h"
#include "HYPRE_IJ_mv.h"
#include "HYPRE_parcsr_ls.h"
#include "_hypre_parcsr_mv.h"

HYPRE_Int agglo_hypre_ij_matrix_create(MPI_Fint comm, HYPRE_BigInt ilower, HYPRE_BigInt iupper,
                                       HYPRE_BigInt jlower, HYPRE_BigInt jupper, HYPRE_IJMatrix *matrix)
{
  return HYPRE_IJMatrixCreate(MPI_Comm_f2c(comm), ilower, iupper, jlower, jupper, matrix);
}

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
