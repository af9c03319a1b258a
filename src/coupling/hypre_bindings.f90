!> Typed interfaces to the part of hypre's C API Agglo uses (hypre 2.26: HYPRE_Int and
!> HYPRE_BigInt are C int, HYPRE_Real and HYPRE_Complex are double; HYPRE_config.h). Objects are
!> opaque pointers (type(c_ptr)), scalars go by value, every function returns hypre's error code.
!> Every interface names its C symbol (bind(C, name=...)): without name= the symbol would be
!> lower-cased and would not link. Calls that take an MPI communicator go through the C shim in
!> hypre_comm_c.c (Fortran's integer handle must be converted with MPI_Comm_f2c).
module hypre_bindings
  use, intrinsic :: iso_c_binding, only: c_int, c_ptr, c_double, c_funptr
  implicit none
  private
  public :: HYPRE_Init, HYPRE_ClearAllErrors
  public :: HYPRE_IJVectorSetObjectType, HYPRE_IJVectorInitialize, HYPRE_IJVectorAssemble, &
            HYPRE_IJVectorGetObject, HYPRE_IJVectorDestroy
  public :: HYPRE_ParCSRBiCGSTABSetTol, HYPRE_ParCSRBiCGSTABSetMaxIter, HYPRE_ParCSRBiCGSTABSetLogging, &
            HYPRE_ParCSRBiCGSTABSetPrintLevel, HYPRE_ParCSRBiCGSTABSetPrecond, HYPRE_ParCSRBiCGSTABSetup, &
            HYPRE_ParCSRBiCGSTABSolve, HYPRE_ParCSRBiCGSTABGetNumIterations, &
            HYPRE_ParCSRBiCGSTABGetFinalRelativeResidualNorm, HYPRE_ParCSRBiCGSTABDestroy
  public :: HYPRE_ParCSRGMRESSetTol, HYPRE_ParCSRGMRESSetMaxIter, HYPRE_ParCSRGMRESSetKDim, &
            HYPRE_ParCSRGMRESSetLogging, HYPRE_ParCSRGMRESSetPrintLevel, HYPRE_ParCSRGMRESSetPrecond, &
            HYPRE_ParCSRGMRESSetup, HYPRE_ParCSRGMRESSolve, HYPRE_ParCSRGMRESGetNumIterations, &
            HYPRE_ParCSRGMRESGetFinalRelativeResidualNorm, HYPRE_ParCSRGMRESDestroy
  public :: HYPRE_BoomerAMGCreate, HYPRE_BoomerAMGDestroy, HYPRE_BoomerAMGSetup, HYPRE_BoomerAMGSolve, &
            HYPRE_BoomerAMGSetMaxIter, HYPRE_BoomerAMGSetCoarsenType, HYPRE_BoomerAMGSetInterpType, &
            HYPRE_BoomerAMGSetPMaxElmts, HYPRE_BoomerAMGSetRelaxType, HYPRE_BoomerAMGSetNumSweeps, &
            HYPRE_BoomerAMGSetPrintLevel, HYPRE_BoomerAMGSetAggNumLevels, HYPRE_BoomerAMGSetTol, &
            HYPRE_BoomerAMGSetStrongThreshold
  public :: HYPRE_ILUCreate, HYPRE_ILUDestroy, HYPRE_ILUSetup, HYPRE_ILUSolve, HYPRE_ILUSetMaxIter, &
            HYPRE_ILUSetType, HYPRE_ILUSetLevelOfFill, HYPRE_ILUSetPrintLevel, HYPRE_ILUSetTol
  public :: agglo_hypre_ij_vector_create, agglo_hypre_bicgstab_create, &
            agglo_hypre_gmres_create, agglo_hypre_par_vector_local_data, agglo_hypre_parcsr_create, &
            agglo_hypre_parcsr_set_rows, HYPRE_ParCSRMatrixDestroy

  integer(c_int), parameter, public :: hypre_parcsr = 5555        !< HYPRE_PARCSR (HYPRE.h)
  integer(c_int), parameter, public :: hypre_error_conv = 256     !< HYPRE_ERROR_CONV (HYPRE_utilities.h)

  interface
    ! Library and errors (HYPRE_utilities.h)
    integer(c_int) function HYPRE_Init() bind(C, name='HYPRE_Init')
      import :: c_int
    end function HYPRE_Init
    integer(c_int) function HYPRE_ClearAllErrors() bind(C, name='HYPRE_ClearAllErrors')
      import :: c_int
    end function HYPRE_ClearAllErrors
    ! IJ vector (HYPRE_IJ_mv.h)
    integer(c_int) function HYPRE_IJVectorSetObjectType(object, object_type) bind(C, name='HYPRE_IJVectorSetObjectType')
      import :: c_int, c_ptr
      type(c_ptr), value :: object
      integer(c_int), value :: object_type
    end function HYPRE_IJVectorSetObjectType
    integer(c_int) function HYPRE_IJVectorInitialize(vector) bind(C, name='HYPRE_IJVectorInitialize')
      import :: c_int, c_ptr
      type(c_ptr), value :: vector
    end function HYPRE_IJVectorInitialize
    integer(c_int) function HYPRE_IJVectorAssemble(vector) bind(C, name='HYPRE_IJVectorAssemble')
      import :: c_int, c_ptr
      type(c_ptr), value :: vector
    end function HYPRE_IJVectorAssemble
    integer(c_int) function HYPRE_IJVectorGetObject(vector, object) bind(C, name='HYPRE_IJVectorGetObject')
      import :: c_int, c_ptr
      type(c_ptr), value :: vector
      type(c_ptr), intent(out) :: object
    end function HYPRE_IJVectorGetObject
    integer(c_int) function HYPRE_IJVectorDestroy(vector) bind(C, name='HYPRE_IJVectorDestroy')
      import :: c_int, c_ptr
      type(c_ptr), value :: vector
    end function HYPRE_IJVectorDestroy
    ! ParCSR BiCGSTAB (HYPRE_parcsr_ls.h); created through the C shim (it takes a communicator)
    integer(c_int) function HYPRE_ParCSRBiCGSTABSetTol(solver, setting) bind(C, name='HYPRE_ParCSRBiCGSTABSetTol')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: solver
      real(c_double), value :: setting
    end function HYPRE_ParCSRBiCGSTABSetTol
    integer(c_int) function HYPRE_ParCSRBiCGSTABSetMaxIter(solver, setting) bind(C, name='HYPRE_ParCSRBiCGSTABSetMaxIter')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ParCSRBiCGSTABSetMaxIter
    integer(c_int) function HYPRE_ParCSRBiCGSTABSetLogging(solver, setting) bind(C, name='HYPRE_ParCSRBiCGSTABSetLogging')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ParCSRBiCGSTABSetLogging
    integer(c_int) function HYPRE_ParCSRBiCGSTABSetPrintLevel(solver, setting) bind(C, name='HYPRE_ParCSRBiCGSTABSetPrintLevel')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ParCSRBiCGSTABSetPrintLevel
    integer(c_int) function HYPRE_ParCSRBiCGSTABSetPrecond(solver, precond, precond_setup, precond_solver) &
        & bind(C, name='HYPRE_ParCSRBiCGSTABSetPrecond')
      import :: c_int, c_ptr, c_funptr
      type(c_ptr), value :: solver
      type(c_funptr), value :: precond, precond_setup
      type(c_ptr), value :: precond_solver
    end function HYPRE_ParCSRBiCGSTABSetPrecond
    integer(c_int) function HYPRE_ParCSRBiCGSTABSetup(solver, matrix, rhs, solution) bind(C, name='HYPRE_ParCSRBiCGSTABSetup')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_ParCSRBiCGSTABSetup
    integer(c_int) function HYPRE_ParCSRBiCGSTABSolve(solver, matrix, rhs, solution) bind(C, name='HYPRE_ParCSRBiCGSTABSolve')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_ParCSRBiCGSTABSolve
    integer(c_int) function HYPRE_ParCSRBiCGSTABGetNumIterations(solver, value_out) &
        & bind(C, name='HYPRE_ParCSRBiCGSTABGetNumIterations')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), intent(out) :: value_out
    end function HYPRE_ParCSRBiCGSTABGetNumIterations
    integer(c_int) function HYPRE_ParCSRBiCGSTABGetFinalRelativeResidualNorm(solver, value_out) &
        & bind(C, name='HYPRE_ParCSRBiCGSTABGetFinalRelativeResidualNorm')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: solver
      real(c_double), intent(out) :: value_out
    end function HYPRE_ParCSRBiCGSTABGetFinalRelativeResidualNorm
    integer(c_int) function HYPRE_ParCSRBiCGSTABDestroy(solver) bind(C, name='HYPRE_ParCSRBiCGSTABDestroy')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
    end function HYPRE_ParCSRBiCGSTABDestroy
    ! ParCSR GMRES (HYPRE_parcsr_ls.h); created through the C shim (it takes a communicator)
    integer(c_int) function HYPRE_ParCSRGMRESSetTol(solver, setting) bind(C, name='HYPRE_ParCSRGMRESSetTol')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: solver
      real(c_double), value :: setting
    end function HYPRE_ParCSRGMRESSetTol
    integer(c_int) function HYPRE_ParCSRGMRESSetMaxIter(solver, setting) bind(C, name='HYPRE_ParCSRGMRESSetMaxIter')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ParCSRGMRESSetMaxIter
    integer(c_int) function HYPRE_ParCSRGMRESSetKDim(solver, setting) bind(C, name='HYPRE_ParCSRGMRESSetKDim')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ParCSRGMRESSetKDim
    integer(c_int) function HYPRE_ParCSRGMRESSetLogging(solver, setting) bind(C, name='HYPRE_ParCSRGMRESSetLogging')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ParCSRGMRESSetLogging
    integer(c_int) function HYPRE_ParCSRGMRESSetPrintLevel(solver, setting) bind(C, name='HYPRE_ParCSRGMRESSetPrintLevel')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ParCSRGMRESSetPrintLevel
    integer(c_int) function HYPRE_ParCSRGMRESSetPrecond(solver, precond, precond_setup, precond_solver) &
        & bind(C, name='HYPRE_ParCSRGMRESSetPrecond')
      import :: c_int, c_ptr, c_funptr
      type(c_ptr), value :: solver
      type(c_funptr), value :: precond, precond_setup
      type(c_ptr), value :: precond_solver
    end function HYPRE_ParCSRGMRESSetPrecond
    integer(c_int) function HYPRE_ParCSRGMRESSetup(solver, matrix, rhs, solution) bind(C, name='HYPRE_ParCSRGMRESSetup')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_ParCSRGMRESSetup
    integer(c_int) function HYPRE_ParCSRGMRESSolve(solver, matrix, rhs, solution) bind(C, name='HYPRE_ParCSRGMRESSolve')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_ParCSRGMRESSolve
    integer(c_int) function HYPRE_ParCSRGMRESGetNumIterations(solver, value_out) bind(C, name='HYPRE_ParCSRGMRESGetNumIterations')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), intent(out) :: value_out
    end function HYPRE_ParCSRGMRESGetNumIterations
    integer(c_int) function HYPRE_ParCSRGMRESGetFinalRelativeResidualNorm(solver, value_out) &
        & bind(C, name='HYPRE_ParCSRGMRESGetFinalRelativeResidualNorm')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: solver
      real(c_double), intent(out) :: value_out
    end function HYPRE_ParCSRGMRESGetFinalRelativeResidualNorm
    integer(c_int) function HYPRE_ParCSRGMRESDestroy(solver) bind(C, name='HYPRE_ParCSRGMRESDestroy')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
    end function HYPRE_ParCSRGMRESDestroy
    ! BoomerAMG (HYPRE_parcsr_ls.h)
    integer(c_int) function HYPRE_BoomerAMGCreate(solver) bind(C, name='HYPRE_BoomerAMGCreate')
      import :: c_int, c_ptr
      type(c_ptr), intent(out) :: solver
    end function HYPRE_BoomerAMGCreate
    integer(c_int) function HYPRE_BoomerAMGDestroy(solver) bind(C, name='HYPRE_BoomerAMGDestroy')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
    end function HYPRE_BoomerAMGDestroy
    integer(c_int) function HYPRE_BoomerAMGSetup(solver, matrix, rhs, solution) bind(C, name='HYPRE_BoomerAMGSetup')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_BoomerAMGSetup
    integer(c_int) function HYPRE_BoomerAMGSolve(solver, matrix, rhs, solution) bind(C, name='HYPRE_BoomerAMGSolve')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_BoomerAMGSolve
    integer(c_int) function HYPRE_BoomerAMGSetMaxIter(solver, setting) bind(C, name='HYPRE_BoomerAMGSetMaxIter')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetMaxIter
    integer(c_int) function HYPRE_BoomerAMGSetCoarsenType(solver, setting) bind(C, name='HYPRE_BoomerAMGSetCoarsenType')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetCoarsenType
    integer(c_int) function HYPRE_BoomerAMGSetInterpType(solver, setting) bind(C, name='HYPRE_BoomerAMGSetInterpType')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetInterpType
    integer(c_int) function HYPRE_BoomerAMGSetPMaxElmts(solver, setting) bind(C, name='HYPRE_BoomerAMGSetPMaxElmts')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetPMaxElmts
    integer(c_int) function HYPRE_BoomerAMGSetRelaxType(solver, setting) bind(C, name='HYPRE_BoomerAMGSetRelaxType')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetRelaxType
    integer(c_int) function HYPRE_BoomerAMGSetNumSweeps(solver, setting) bind(C, name='HYPRE_BoomerAMGSetNumSweeps')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetNumSweeps
    integer(c_int) function HYPRE_BoomerAMGSetPrintLevel(solver, setting) bind(C, name='HYPRE_BoomerAMGSetPrintLevel')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetPrintLevel
    integer(c_int) function HYPRE_BoomerAMGSetAggNumLevels(solver, setting) bind(C, name='HYPRE_BoomerAMGSetAggNumLevels')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_BoomerAMGSetAggNumLevels
    integer(c_int) function HYPRE_BoomerAMGSetTol(solver, setting) bind(C, name='HYPRE_BoomerAMGSetTol')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: solver
      real(c_double), value :: setting
    end function HYPRE_BoomerAMGSetTol
    integer(c_int) function HYPRE_BoomerAMGSetStrongThreshold(solver, setting) bind(C, name='HYPRE_BoomerAMGSetStrongThreshold')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: solver
      real(c_double), value :: setting
    end function HYPRE_BoomerAMGSetStrongThreshold
    ! ILU (HYPRE_parcsr_ls.h, hypre >= 2.20)
    integer(c_int) function HYPRE_ILUCreate(solver) bind(C, name='HYPRE_ILUCreate')
      import :: c_int, c_ptr
      type(c_ptr), intent(out) :: solver
    end function HYPRE_ILUCreate
    integer(c_int) function HYPRE_ILUDestroy(solver) bind(C, name='HYPRE_ILUDestroy')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
    end function HYPRE_ILUDestroy
    integer(c_int) function HYPRE_ILUSetup(solver, matrix, rhs, solution) bind(C, name='HYPRE_ILUSetup')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_ILUSetup
    integer(c_int) function HYPRE_ILUSolve(solver, matrix, rhs, solution) bind(C, name='HYPRE_ILUSolve')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver, matrix, rhs, solution
    end function HYPRE_ILUSolve
    integer(c_int) function HYPRE_ILUSetMaxIter(solver, setting) bind(C, name='HYPRE_ILUSetMaxIter')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ILUSetMaxIter
    integer(c_int) function HYPRE_ILUSetType(solver, setting) bind(C, name='HYPRE_ILUSetType')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ILUSetType
    integer(c_int) function HYPRE_ILUSetLevelOfFill(solver, setting) bind(C, name='HYPRE_ILUSetLevelOfFill')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ILUSetLevelOfFill
    integer(c_int) function HYPRE_ILUSetPrintLevel(solver, setting) bind(C, name='HYPRE_ILUSetPrintLevel')
      import :: c_int, c_ptr
      type(c_ptr), value :: solver
      integer(c_int), value :: setting
    end function HYPRE_ILUSetPrintLevel
    integer(c_int) function HYPRE_ILUSetTol(solver, setting) bind(C, name='HYPRE_ILUSetTol')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: solver
      real(c_double), value :: setting
    end function HYPRE_ILUSetTol
    ! ParCSR matrix (HYPRE_parcsr_mv.h)
    integer(c_int) function HYPRE_ParCSRMatrixDestroy(matrix) bind(C, name='HYPRE_ParCSRMatrixDestroy')
      import :: c_int, c_ptr
      type(c_ptr), value :: matrix
    end function HYPRE_ParCSRMatrixDestroy
    ! The C shim (hypre_comm_c.c): communicator conversion and the local part of a ParVector
    integer(c_int) function agglo_hypre_ij_vector_create(comm, jlower, jupper, vector) bind(C, name='agglo_hypre_ij_vector_create')
      import :: c_int, c_ptr
      integer(c_int), value :: comm, jlower, jupper
      type(c_ptr), intent(out) :: vector
    end function agglo_hypre_ij_vector_create
    integer(c_int) function agglo_hypre_bicgstab_create(comm, solver) bind(C, name='agglo_hypre_bicgstab_create')
      import :: c_int, c_ptr
      integer(c_int), value :: comm
      type(c_ptr), intent(out) :: solver
    end function agglo_hypre_bicgstab_create
    integer(c_int) function agglo_hypre_gmres_create(comm, solver) bind(C, name='agglo_hypre_gmres_create')
      import :: c_int, c_ptr
      integer(c_int), value :: comm
      type(c_ptr), intent(out) :: solver
    end function agglo_hypre_gmres_create
    !> Pointer to this rank's entries of a HYPRE_ParVector (contiguous, its rows in order); size
    !> receives their number (hypre_comm_c.c).
    type(c_ptr) function agglo_hypre_par_vector_local_data(vector, size) &
        bind(C, name='agglo_hypre_par_vector_local_data')
      import :: c_int, c_ptr
      type(c_ptr), value :: vector
      integer(c_int), intent(out) :: size
    end function agglo_hypre_par_vector_local_data
    !> A ParCSR matrix from this rank's rows in CSR form (sparse_rows_t's layout; hypre_comm_c.c).
    !> Rows over_rows (ascending) come from the compact CSR over_start, over_columns, over_values.
    integer(c_int) function agglo_hypre_parcsr_create(comm, first_row, last_row, global_rows, row_start, columns, &
        values, n_over, over_rows, over_start, over_columns, over_values, matrix) bind(C, name='agglo_hypre_parcsr_create')
      import :: c_int, c_ptr, c_double
      integer(c_int), value :: comm, first_row, last_row, global_rows, n_over
      integer(c_int), intent(in) :: row_start(*), columns(*), over_rows(*), over_start(*), over_columns(*)
      real(c_double), intent(in) :: values(*), over_values(*)
      type(c_ptr), intent(out) :: matrix
    end function agglo_hypre_parcsr_create
    !> New values of listed local rows (1-based), in compact CSR form, on the matrix's pattern.
    integer(c_int) function agglo_hypre_parcsr_set_rows(matrix, n_set, rows, row_start, columns, values) &
        bind(C, name='agglo_hypre_parcsr_set_rows')
      import :: c_int, c_ptr, c_double
      type(c_ptr), value :: matrix
      integer(c_int), value :: n_set
      integer(c_int), intent(in) :: rows(*), row_start(*), columns(*)
      real(c_double), intent(in) :: values(*)
    end function agglo_hypre_parcsr_set_rows
  end interface
end module hypre_bindings
