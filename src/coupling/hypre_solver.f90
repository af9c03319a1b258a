!> A sparse linear system A x = b distributed over the ranks by contiguous blocks of global rows,
!> solved with hypre's ParCSR Krylov methods (docs/theory.md, "Linear solver (hypre)").
!>
!> Each rank hands over its block of rows in CSR form (sparse_rows_t): global rows
!> first_row .. last_row, numbered from 1 and contiguous per rank in rank order, exactly as
!> hypre_helmholtz_rows numbers the unknowns of a slab-decomposed field. The solver builds hypre's
!> ParCSR matrix straight from those rows (hypre_comm_c.c: two linear passes, where the IJ
!> interface's SetValues + Assemble hash and sort every entry), keeps it across solves
!> (linear_solver_update_values writes new values of all or some rows into it in place;
!> linear_solver_replace_matrix swaps in a matrix of another pattern and keeps the vectors and the
!> Krylov solver) and solves with BiCGSTAB or GMRES preconditioned by BoomerAMG, ILU(0), nothing,
!> or a caller's preconditioner (user_preconditioner_t, e.g. the FFT Helmholtz solve). Every solve returns a
!> solve_status_t; the caller decides whether non-convergence stops the run (solve_status_text
!> gives the message with both numbers and the advice).
module hypre_solver
  use, intrinsic :: iso_c_binding, only: c_int, c_double, c_ptr, c_null_ptr, c_associated, c_loc, c_funloc, &
                                         c_f_pointer
  use mpi_f08, only: MPI_Comm, MPI_Allreduce, MPI_IN_PLACE, MPI_INTEGER, MPI_MAX
  use agglo_kinds, only: wp
  use parallel_env, only: world
  use error_handling, only: fatal
  use timer_registry, only: timer_register, timer_tic, timer_toc
  use hypre_bindings, only: hypre_parcsr, hypre_error_conv, HYPRE_Init, HYPRE_ClearAllErrors, &
      HYPRE_ParCSRMatrixDestroy, agglo_hypre_parcsr_create, agglo_hypre_parcsr_set_rows, &
      HYPRE_IJVectorSetObjectType, HYPRE_IJVectorInitialize, HYPRE_IJVectorAssemble, HYPRE_IJVectorGetObject, &
      HYPRE_IJVectorDestroy, &
      HYPRE_ParCSRBiCGSTABSetTol, HYPRE_ParCSRBiCGSTABSetMaxIter, HYPRE_ParCSRBiCGSTABSetLogging, &
      HYPRE_ParCSRBiCGSTABSetPrintLevel, HYPRE_ParCSRBiCGSTABSetPrecond, HYPRE_ParCSRBiCGSTABSetup, &
      HYPRE_ParCSRBiCGSTABSolve, HYPRE_ParCSRBiCGSTABGetNumIterations, &
      HYPRE_ParCSRBiCGSTABGetFinalRelativeResidualNorm, HYPRE_ParCSRBiCGSTABDestroy, &
      HYPRE_ParCSRGMRESSetTol, HYPRE_ParCSRGMRESSetMaxIter, HYPRE_ParCSRGMRESSetKDim, HYPRE_ParCSRGMRESSetLogging, &
      HYPRE_ParCSRGMRESSetPrintLevel, HYPRE_ParCSRGMRESSetPrecond, HYPRE_ParCSRGMRESSetup, HYPRE_ParCSRGMRESSolve, &
      HYPRE_ParCSRGMRESGetNumIterations, HYPRE_ParCSRGMRESGetFinalRelativeResidualNorm, HYPRE_ParCSRGMRESDestroy, &
      HYPRE_BoomerAMGCreate, HYPRE_BoomerAMGDestroy, HYPRE_BoomerAMGSetup, HYPRE_BoomerAMGSolve, &
      HYPRE_BoomerAMGSetMaxIter, HYPRE_BoomerAMGSetCoarsenType, HYPRE_BoomerAMGSetInterpType, &
      HYPRE_BoomerAMGSetPMaxElmts, HYPRE_BoomerAMGSetRelaxType, HYPRE_BoomerAMGSetNumSweeps, &
      HYPRE_BoomerAMGSetPrintLevel, HYPRE_BoomerAMGSetTol, HYPRE_BoomerAMGSetStrongThreshold, &
      HYPRE_ILUCreate, HYPRE_ILUDestroy, HYPRE_ILUSetup, HYPRE_ILUSolve, HYPRE_ILUSetMaxIter, HYPRE_ILUSetType, &
      HYPRE_ILUSetLevelOfFill, HYPRE_ILUSetPrintLevel, HYPRE_ILUSetTol, &
      agglo_hypre_ij_vector_create, agglo_hypre_bicgstab_create, &
      agglo_hypre_gmres_create, agglo_hypre_par_vector_local_data
  implicit none
  private
  public :: sparse_rows_t, linear_solver_config_t, solve_status_t, user_preconditioner_t, linear_solver_t
  public :: linear_solver_create, linear_solver_update_values, linear_solver_replace_matrix, linear_solver_solve, &
            linear_solver_destroy, solve_status_text, rows_local_count
  public :: solver_methods, solver_preconditioners

  character(len=*), parameter :: solver_methods = 'bicgstab, gmres'
  character(len=*), parameter :: solver_preconditioners = 'boomeramg, ilu, none, user'

  !> This rank's block of rows in CSR form. Global indices start at 1; the entries of local row r
  !> (global row first_row + r - 1) are row_start(r) .. row_start(r + 1) - 1 of columns/values.
  type :: sparse_rows_t
    integer :: first_row = 1, last_row = 0
    integer, allocatable :: row_start(:)      !< (rows_local_count + 1)
    integer, allocatable :: columns(:)        !< global column of each entry
    real(wp), allocatable :: values(:)        !< matrix entry of each entry
  end type sparse_rows_t

  !> The method, its preconditioner and the stopping rule.
  type :: linear_solver_config_t
    character(len=16) :: method = 'bicgstab'            !< 'bicgstab' | 'gmres'
    character(len=16) :: preconditioner = 'boomeramg'   !< 'boomeramg' | 'ilu' | 'none' | 'user'
    real(wp) :: tolerance = 1.0e-10_wp                  !< on ||b - A x||_2 / ||b||_2 (hypre's default criterion)
    integer :: max_iterations = 200
    integer :: gmres_restart = 30                       !< Krylov dimension before GMRES restarts
  end type linear_solver_config_t

  !> The outcome of one solve (in the manner of fortran-lang stdlib's status objects: the library
  !> reports, the caller decides whether to stop).
  type :: solve_status_t
    logical :: converged = .false.
    integer :: iterations = 0
    real(wp) :: relative_residual = huge(1.0_wp)   !< hypre's final ||b - A x|| / ||b||
    real(wp) :: tolerance = 0                      !< the settings it was measured against
    integer :: max_iterations = 0
  end type solve_status_t

  !> A caller's preconditioner: correction ~ A^{-1} residual on this rank's rows (both arrays
  !> have rows_local_count entries, in row order). It may communicate (e.g. an FFT): every rank
  !> calls it at the same time, once per Krylov application.
  type, abstract :: user_preconditioner_t
  contains
    procedure(apply_interface), deferred :: apply
  end type user_preconditioner_t

  abstract interface
    subroutine apply_interface(self, residual, correction)
      import :: user_preconditioner_t, wp
      class(user_preconditioner_t), intent(inout) :: self
      real(wp), intent(in) :: residual(:)
      real(wp), intent(out) :: correction(:)
    end subroutine apply_interface
  end interface

  !> What hypre hands back to the preconditioner callbacks as their "solver": the caller's object.
  type :: user_handle_t
    class(user_preconditioner_t), pointer :: user => null()
  end type user_handle_t

  type :: linear_solver_t
    private
    type(linear_solver_config_t) :: config
    integer(c_int) :: communicator = 0             !< Fortran handle of the ranks that share the system
    integer :: first_row = 1, last_row = 0, n_entries = 0, global_rows = 0
    integer :: timer_matrix = 0                    !< 'hypre matrices' (timer_registry): building, new values
    type(c_ptr) :: matrix = c_null_ptr             !< the ParCSR matrix (hypre_comm_c.c)
    type(c_ptr) :: ij_rhs = c_null_ptr, rhs = c_null_ptr, ij_solution = c_null_ptr, solution = c_null_ptr
    type(c_ptr) :: krylov = c_null_ptr, precond = c_null_ptr
    real(c_double), pointer, contiguous :: rhs_local(:) => null(), solution_local(:) => null()
    type(user_handle_t), pointer :: handle => null()
    logical :: set_up = .false.                    !< Krylov and preconditioner set up for the current values
  end type linear_solver_t

  logical :: hypre_started = .false.

contains

  pure integer function rows_local_count(rows)
    type(sparse_rows_t), intent(in) :: rows
    rows_local_count = rows%last_row - rows%first_row + 1
  end function rows_local_count

  !> Assemble the matrix of this rank's rows and make the Krylov solver and its preconditioner
  !> (collective over communicator, by default every rank). preconditioner must be given when
  !> config%preconditioner = 'user'; the solver keeps a pointer to it, so the actual argument must
  !> have the target attribute and outlive the solver.
  subroutine linear_solver_create(solver, rows, config, preconditioner, communicator, replaced, replaced_rows)
    type(linear_solver_t), intent(inout) :: solver
    type(sparse_rows_t), intent(in) :: rows
    type(linear_solver_config_t), intent(in) :: config
    class(user_preconditioner_t), intent(inout), target, optional :: preconditioner
    type(MPI_Comm), intent(in), optional :: communicator
    type(sparse_rows_t), intent(in), optional :: replaced   !< rows replacing those of rows (build_matrix)
    integer, intent(in), optional :: replaced_rows(:)
    type(MPI_Comm) :: comm

    call check_config(config, present(preconditioner))
    call linear_solver_destroy(solver)
    if (.not. hypre_started) then
      call require_ok(HYPRE_Init(), 'HYPRE_Init')
      hypre_started = .true.
    end if
    solver%timer_matrix = timer_register('hypre matrices')
    solver%config = config
    comm = world
    if (present(communicator)) comm = communicator
    solver%communicator = int(comm%MPI_VAL, c_int)
    solver%first_row = rows%first_row
    solver%last_row = rows%last_row
    solver%global_rows = rows%last_row
    call MPI_Allreduce(MPI_IN_PLACE, solver%global_rows, 1, MPI_INTEGER, MPI_MAX, comm)
    call build_matrix(solver, rows, replaced, replaced_rows)

    call make_vector(solver, solver%ij_rhs, solver%rhs, solver%rhs_local)
    call make_vector(solver, solver%ij_solution, solver%solution, solver%solution_local)
    if (present(preconditioner)) then
      allocate(solver%handle)
      solver%handle%user => preconditioner
    end if
    call make_krylov(solver)
  end subroutine linear_solver_create

  !> New values on the same sparsity pattern (e.g. a new dt, or ghost weights after a sub-cell
  !> move), written into the matrix in place: all rows, or only the local rows listed in
  !> changed_rows (ascending or not; then rows holds just those rows, in that order, in compact
  !> CSR form: the entries of the s-th listed row are row_start(s) .. row_start(s + 1) - 1).
  !> A row whose pattern differs from the matrix's stops the run. With BoomerAMG or ILU the
  !> preconditioner is set up again on the next solve; the FFT (user) preconditioner and none have
  !> no set-up that depends on the values, so the Krylov solver is kept as it is.
  subroutine linear_solver_update_values(solver, rows, changed_rows)
    type(linear_solver_t), intent(inout) :: solver
    type(sparse_rows_t), intent(in) :: rows
    integer, intent(in), optional :: changed_rows(:)
    character(len=200) :: text
    integer :: r
    integer(c_int) :: ierr
    call timer_tic(solver%timer_matrix)
    if (present(changed_rows)) then
      ierr = agglo_hypre_parcsr_set_rows(solver%matrix, int(size(changed_rows), c_int), int(changed_rows, c_int), &
                                         int(rows%row_start, c_int), int(rows%columns, c_int), real(rows%values, c_double))
    else if (rows%first_row /= solver%first_row .or. rows%last_row /= solver%last_row .or. &
             rows%row_start(rows_local_count(rows) + 1) - 1 /= solver%n_entries) then
      ierr = 1
    else
      ierr = agglo_hypre_parcsr_set_rows(solver%matrix, int(rows_local_count(rows), c_int), &
                                         [(int(r, c_int), r = 1, rows_local_count(rows))], int(rows%row_start, c_int), &
                                         int(rows%columns, c_int), real(rows%values, c_double))
    end if
    if (ierr /= 0) then
      write(text, '(a,i0,a,i0,a)') 'linear_solver_update_values: the rows (', rows%first_row, ' .. ', &
          rows%last_row, ') do not have the structure the solver was created with; create a new solver'
      call fatal(trim(text), collective=.false.)
    end if
    if (solver%config%preconditioner == 'boomeramg' .or. solver%config%preconditioner == 'ilu') then
      ! Their setup builds the hierarchy / factors from the values: new Krylov and preconditioner objects.
      call destroy_krylov(solver)
      call make_krylov(solver)
    end if
    call timer_toc(solver%timer_matrix)
  end subroutine linear_solver_update_values

  !> A matrix of another sparsity pattern on the same rows (e.g. nodes that changed status): the
  !> new ParCSR matrix replaces the old one; the vectors and the Krylov solver are kept (its next
  !> solve sets it up on the new matrix: with the FFT preconditioner that allocates nothing).
  subroutine linear_solver_replace_matrix(solver, rows, replaced, replaced_rows)
    type(linear_solver_t), intent(inout) :: solver
    type(sparse_rows_t), intent(in) :: rows
    type(sparse_rows_t), intent(in), optional :: replaced   !< rows replacing those of rows (build_matrix)
    integer, intent(in), optional :: replaced_rows(:)
    character(len=200) :: text
    if (rows%first_row /= solver%first_row .or. rows%last_row /= solver%last_row) then
      write(text, '(a,i0,a,i0,a,i0,a,i0,a)') 'linear_solver_replace_matrix: rows ', rows%first_row, ' .. ', &
          rows%last_row, ' instead of the solver''s ', solver%first_row, ' .. ', solver%last_row, '; create a new solver'
      call fatal(trim(text), collective=.false.)
    end if
    call build_matrix(solver, rows, replaced, replaced_rows)
    if (solver%config%preconditioner == 'boomeramg' .or. solver%config%preconditioner == 'ilu') then
      call destroy_krylov(solver)
      call make_krylov(solver)
    end if
    solver%set_up = .false.
  end subroutine linear_solver_replace_matrix

  !> Solve A solution = rhs on this rank's rows (collective). solution holds the initial guess on
  !> entry (e.g. the previous time level). The first solve after create or update_values also
  !> sets up the preconditioner.
  subroutine linear_solver_solve(solver, rhs, solution, status)
    type(linear_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: rhs(:)
    real(wp), intent(inout) :: solution(:)
    type(solve_status_t), intent(out) :: status
    integer(c_int) :: ierr, iterations
    real(c_double) :: residual
    character(len=160) :: text

    if (size(rhs) /= size(solver%rhs_local) .or. size(solution) /= size(solver%rhs_local)) then
      write(text, '(a,i0,a,i0,a,i0)') 'linear_solver_solve: rhs has ', size(rhs), ' and solution ', &
          size(solution), ' entries, this rank owns ', size(solver%rhs_local)
      call fatal(trim(text), collective=.false.)
    end if
    ! Every hypre solve of the run under one timer (the step's breakdown, docs/studies/performance.md).
    call timer_tic('hypre')
    solver%rhs_local = rhs
    solver%solution_local = solution
    select case (solver%config%method)
    case ('bicgstab')
      if (.not. solver%set_up) call require_ok(HYPRE_ParCSRBiCGSTABSetup(solver%krylov, solver%matrix, solver%rhs, &
                                               solver%solution), 'HYPRE_ParCSRBiCGSTABSetup')
      ierr = accept_non_convergence(HYPRE_ParCSRBiCGSTABSolve(solver%krylov, solver%matrix, solver%rhs, &
                                    solver%solution))
      call require_ok(HYPRE_ParCSRBiCGSTABGetNumIterations(solver%krylov, iterations), 'GetNumIterations')
      call require_ok(HYPRE_ParCSRBiCGSTABGetFinalRelativeResidualNorm(solver%krylov, residual), &
                      'GetFinalRelativeResidualNorm')
    case default
      if (.not. solver%set_up) call require_ok(HYPRE_ParCSRGMRESSetup(solver%krylov, solver%matrix, solver%rhs, &
                                               solver%solution), 'HYPRE_ParCSRGMRESSetup')
      ierr = accept_non_convergence(HYPRE_ParCSRGMRESSolve(solver%krylov, solver%matrix, solver%rhs, &
                                    solver%solution))
      call require_ok(HYPRE_ParCSRGMRESGetNumIterations(solver%krylov, iterations), 'GetNumIterations')
      call require_ok(HYPRE_ParCSRGMRESGetFinalRelativeResidualNorm(solver%krylov, residual), &
                      'GetFinalRelativeResidualNorm')
    end select
    solver%set_up = .true.
    call require_ok(ierr, 'HYPRE_ParCSR'//trim(solver%config%method)//'Solve')
    solution = solver%solution_local
    call timer_toc('hypre')
    status%iterations = int(iterations)
    status%relative_residual = real(residual, wp)
    status%tolerance = solver%config%tolerance
    status%max_iterations = solver%config%max_iterations
    status%converged = (status%relative_residual <= status%tolerance)   ! NaN: not converged
  end subroutine linear_solver_solve

  !> Release every hypre object (collective); safe on a solver never created.
  subroutine linear_solver_destroy(solver)
    type(linear_solver_t), intent(inout) :: solver
    call destroy_krylov(solver)
    if (c_associated(solver%matrix)) call require_ok(HYPRE_ParCSRMatrixDestroy(solver%matrix), &
                                                     'HYPRE_ParCSRMatrixDestroy')
    if (c_associated(solver%ij_rhs)) call require_ok(HYPRE_IJVectorDestroy(solver%ij_rhs), 'HYPRE_IJVectorDestroy')
    if (c_associated(solver%ij_solution)) call require_ok(HYPRE_IJVectorDestroy(solver%ij_solution), &
                                                          'HYPRE_IJVectorDestroy')
    solver%matrix = c_null_ptr
    solver%ij_rhs = c_null_ptr; solver%rhs = c_null_ptr; solver%ij_solution = c_null_ptr; solver%solution = c_null_ptr
    solver%rhs_local => null(); solver%solution_local => null()
    if (associated(solver%handle)) deallocate(solver%handle)
  end subroutine linear_solver_destroy

  !> One line for the log: method, iterations, residual and, if it did not converge, the advice.
  function solve_status_text(status, config) result(text)
    type(solve_status_t), intent(in) :: status
    type(linear_solver_config_t), intent(in) :: config
    character(len=:), allocatable :: text
    character(len=320) :: line
    if (status%converged) then
      write(line, '(a,i0,a,es9.2,a,es9.2,a)') trim(config%method)//' + '//trim(config%preconditioner)//': ', &
          status%iterations, ' iterations, relative residual ', status%relative_residual, ' (tolerance ', &
          status%tolerance, ')'
    else
      write(line, '(a,i0,a,es9.2,a,es9.2,a,i0,a)') trim(config%method)//' + '//trim(config%preconditioner)// &
          ': not converged after ', status%iterations, ' iterations: relative residual ', status%relative_residual, &
          ' > tolerance ', status%tolerance, ' (max_iterations ', status%max_iterations, &
          '); reduce dt, raise max_iterations or loosen the tolerance, or try another preconditioner'
    end if
    text = trim(line)
  end function solve_status_text

  ! ---------------------------------------------------------------------------------------------

  subroutine check_config(config, has_preconditioner)
    type(linear_solver_config_t), intent(in) :: config
    logical, intent(in) :: has_preconditioner
    character(len=200) :: text
    if (index(', '//solver_methods//',', ', '//trim(config%method)//',') == 0) &
        call fatal('linear solver: method '''//trim(config%method)//''' is not one of '//solver_methods)
    if (index(', '//solver_preconditioners//',', ', '//trim(config%preconditioner)//',') == 0) &
        call fatal('linear solver: preconditioner '''//trim(config%preconditioner)//''' is not one of '// &
                   solver_preconditioners)
    if ((config%preconditioner == 'user') .neqv. has_preconditioner) &
        call fatal('linear solver: a preconditioner object is given exactly when preconditioner = ''user''')
    if (.not. (config%tolerance > 0.0_wp .and. config%tolerance < 1.0_wp) .or. config%max_iterations < 1 &
        .or. config%gmres_restart < 1) then
      write(text, '(a,es10.3,a,i0,a,i0,a)') 'linear solver: tolerance ', config%tolerance, ', max_iterations ', &
          config%max_iterations, ', gmres_restart ', config%gmres_restart, &
          ' (allowed: 0 < tolerance < 1, max_iterations >= 1, gmres_restart >= 1)'
      call fatal(trim(text))
    end if
  end subroutine check_config

  !> The ParCSR matrix of this rank's rows (collective), replacing the solver's if it has one.
  !> replaced_rows (ascending local rows) take their entries from replaced (compact CSR: those of
  !> the s-th are replaced%row_start(s) .. replaced%row_start(s + 1) - 1) instead of from rows.
  !> The arrays go to C as they are (default integer and real(wp) are c_int and c_double).
  subroutine build_matrix(solver, rows, replaced, replaced_rows)
    type(linear_solver_t), intent(inout) :: solver
    type(sparse_rows_t), intent(in) :: rows
    type(sparse_rows_t), intent(in), optional :: replaced
    integer, intent(in), optional :: replaced_rows(:)
    integer, parameter :: none(1) = 0
    real(wp), parameter :: no_values(1) = 0
    integer :: n_entries, s
    integer(c_int) :: ierr
    call timer_tic(solver%timer_matrix)
    if (c_associated(solver%matrix)) call require_ok(HYPRE_ParCSRMatrixDestroy(solver%matrix), &
                                                     'HYPRE_ParCSRMatrixDestroy')
    n_entries = rows%row_start(rows_local_count(rows) + 1) - 1
    if (present(replaced) .and. present(replaced_rows)) then
      n_entries = n_entries + replaced%row_start(size(replaced_rows) + 1) - 1
      do s = 1, size(replaced_rows)
        n_entries = n_entries - (rows%row_start(replaced_rows(s) + 1) - rows%row_start(replaced_rows(s)))
      end do
      ierr = agglo_hypre_parcsr_create(solver%communicator, rows%first_row, rows%last_row, solver%global_rows, &
                                       rows%row_start, rows%columns, rows%values, size(replaced_rows), replaced_rows, &
                                       replaced%row_start, replaced%columns, replaced%values, solver%matrix)
    else
      ierr = agglo_hypre_parcsr_create(solver%communicator, rows%first_row, rows%last_row, solver%global_rows, &
                                       rows%row_start, rows%columns, rows%values, 0, none, none, none, no_values, &
                                       solver%matrix)
    end if
    call require_ok(ierr, 'agglo_hypre_parcsr_create')
    solver%n_entries = n_entries
    call timer_toc(solver%timer_matrix)
  end subroutine build_matrix

  !> An assembled ParCSR vector on this rank's rows and a Fortran view of its local entries.
  subroutine make_vector(solver, ij_vector, vector, local)
    type(linear_solver_t), intent(in) :: solver
    type(c_ptr), intent(out) :: ij_vector, vector
    real(c_double), pointer, contiguous, intent(out) :: local(:)
    call require_ok(agglo_hypre_ij_vector_create(solver%communicator, solver%first_row, solver%last_row, ij_vector), &
                    'HYPRE_IJVectorCreate')
    call require_ok(HYPRE_IJVectorSetObjectType(ij_vector, hypre_parcsr), 'HYPRE_IJVectorSetObjectType')
    call require_ok(HYPRE_IJVectorInitialize(ij_vector), 'HYPRE_IJVectorInitialize')
    call require_ok(HYPRE_IJVectorAssemble(ij_vector), 'HYPRE_IJVectorAssemble')
    call require_ok(HYPRE_IJVectorGetObject(ij_vector, vector), 'HYPRE_IJVectorGetObject')
    local => local_view(vector)
    local = 0.0_c_double
  end subroutine make_vector

  !> The Krylov solver with its settings and preconditioner (collective).
  subroutine make_krylov(solver)
    type(linear_solver_t), intent(inout) :: solver
    type(c_ptr) :: precond_solver
    call make_preconditioner(solver)
    precond_solver = solver%precond
    if (solver%config%preconditioner == 'user') precond_solver = c_loc(solver%handle)
    select case (solver%config%method)
    case ('bicgstab')
      call require_ok(agglo_hypre_bicgstab_create(solver%communicator, solver%krylov), 'HYPRE_ParCSRBiCGSTABCreate')
      call require_ok(HYPRE_ParCSRBiCGSTABSetTol(solver%krylov, real(solver%config%tolerance, c_double)), 'SetTol')
      call require_ok(HYPRE_ParCSRBiCGSTABSetMaxIter(solver%krylov, int(solver%config%max_iterations, c_int)), &
                      'SetMaxIter')
      call require_ok(HYPRE_ParCSRBiCGSTABSetLogging(solver%krylov, 1_c_int), 'SetLogging')
      call require_ok(HYPRE_ParCSRBiCGSTABSetPrintLevel(solver%krylov, 0_c_int), 'SetPrintLevel')
      select case (solver%config%preconditioner)
      case ('boomeramg')
        call require_ok(HYPRE_ParCSRBiCGSTABSetPrecond(solver%krylov, c_funloc(HYPRE_BoomerAMGSolve), &
                        c_funloc(HYPRE_BoomerAMGSetup), precond_solver), 'SetPrecond')
      case ('ilu')
        call require_ok(HYPRE_ParCSRBiCGSTABSetPrecond(solver%krylov, c_funloc(HYPRE_ILUSolve), &
                        c_funloc(HYPRE_ILUSetup), precond_solver), 'SetPrecond')
      case ('user')
        call require_ok(HYPRE_ParCSRBiCGSTABSetPrecond(solver%krylov, c_funloc(apply_user_preconditioner), &
                        c_funloc(set_up_user_preconditioner), precond_solver), 'SetPrecond')
      end select
    case ('gmres')
      call require_ok(agglo_hypre_gmres_create(solver%communicator, solver%krylov), 'HYPRE_ParCSRGMRESCreate')
      call require_ok(HYPRE_ParCSRGMRESSetTol(solver%krylov, real(solver%config%tolerance, c_double)), 'SetTol')
      call require_ok(HYPRE_ParCSRGMRESSetMaxIter(solver%krylov, int(solver%config%max_iterations, c_int)), &
                      'SetMaxIter')
      call require_ok(HYPRE_ParCSRGMRESSetKDim(solver%krylov, int(solver%config%gmres_restart, c_int)), 'SetKDim')
      call require_ok(HYPRE_ParCSRGMRESSetLogging(solver%krylov, 1_c_int), 'SetLogging')
      call require_ok(HYPRE_ParCSRGMRESSetPrintLevel(solver%krylov, 0_c_int), 'SetPrintLevel')
      select case (solver%config%preconditioner)
      case ('boomeramg')
        call require_ok(HYPRE_ParCSRGMRESSetPrecond(solver%krylov, c_funloc(HYPRE_BoomerAMGSolve), &
                        c_funloc(HYPRE_BoomerAMGSetup), precond_solver), 'SetPrecond')
      case ('ilu')
        call require_ok(HYPRE_ParCSRGMRESSetPrecond(solver%krylov, c_funloc(HYPRE_ILUSolve), &
                        c_funloc(HYPRE_ILUSetup), precond_solver), 'SetPrecond')
      case ('user')
        call require_ok(HYPRE_ParCSRGMRESSetPrecond(solver%krylov, c_funloc(apply_user_preconditioner), &
                        c_funloc(set_up_user_preconditioner), precond_solver), 'SetPrecond')
      end select
    end select
    solver%set_up = .false.
  end subroutine make_krylov

  !> hypre's preconditioners, each as one cycle / one sweep (max_iter 1, tol 0: a fixed linear
  !> operator, as a Krylov preconditioner must be).
  subroutine make_preconditioner(solver)
    type(linear_solver_t), intent(inout) :: solver
    select case (solver%config%preconditioner)
    case ('boomeramg')
      ! The reference manual's settings for 3-D problems on many cores: HMIS coarsening (10),
      ! extended+i interpolation (6) truncated to 4 entries per row, strength threshold 0.5 for
      ! 3-D; hybrid symmetric Gauss-Seidel smoothing (6), one sweep.
      call require_ok(HYPRE_BoomerAMGCreate(solver%precond), 'HYPRE_BoomerAMGCreate')
      call require_ok(HYPRE_BoomerAMGSetPrintLevel(solver%precond, 0_c_int), 'SetPrintLevel')
      call require_ok(HYPRE_BoomerAMGSetCoarsenType(solver%precond, 10_c_int), 'SetCoarsenType')
      call require_ok(HYPRE_BoomerAMGSetInterpType(solver%precond, 6_c_int), 'SetInterpType')
      call require_ok(HYPRE_BoomerAMGSetPMaxElmts(solver%precond, 4_c_int), 'SetPMaxElmts')
      call require_ok(HYPRE_BoomerAMGSetStrongThreshold(solver%precond, 0.5_c_double), 'SetStrongThreshold')
      call require_ok(HYPRE_BoomerAMGSetRelaxType(solver%precond, 6_c_int), 'SetRelaxType')
      call require_ok(HYPRE_BoomerAMGSetNumSweeps(solver%precond, 1_c_int), 'SetNumSweeps')
      call require_ok(HYPRE_BoomerAMGSetMaxIter(solver%precond, 1_c_int), 'SetMaxIter')
      call require_ok(HYPRE_BoomerAMGSetTol(solver%precond, 0.0_c_double), 'SetTol')
    case ('ilu')
      ! Block-Jacobi ILU(0): type 0, level of fill 0, each rank factors its diagonal block.
      call require_ok(HYPRE_ILUCreate(solver%precond), 'HYPRE_ILUCreate')
      call require_ok(HYPRE_ILUSetPrintLevel(solver%precond, 0_c_int), 'SetPrintLevel')
      call require_ok(HYPRE_ILUSetType(solver%precond, 0_c_int), 'SetType')
      call require_ok(HYPRE_ILUSetLevelOfFill(solver%precond, 0_c_int), 'SetLevelOfFill')
      call require_ok(HYPRE_ILUSetMaxIter(solver%precond, 1_c_int), 'SetMaxIter')
      call require_ok(HYPRE_ILUSetTol(solver%precond, 0.0_c_double), 'SetTol')
    end select
  end subroutine make_preconditioner

  subroutine destroy_krylov(solver)
    type(linear_solver_t), intent(inout) :: solver
    if (c_associated(solver%krylov)) then
      select case (solver%config%method)
      case ('bicgstab'); call require_ok(HYPRE_ParCSRBiCGSTABDestroy(solver%krylov), 'HYPRE_ParCSRBiCGSTABDestroy')
      case ('gmres'); call require_ok(HYPRE_ParCSRGMRESDestroy(solver%krylov), 'HYPRE_ParCSRGMRESDestroy')
      end select
    end if
    if (c_associated(solver%precond)) then
      select case (solver%config%preconditioner)
      case ('boomeramg'); call require_ok(HYPRE_BoomerAMGDestroy(solver%precond), 'HYPRE_BoomerAMGDestroy')
      case ('ilu'); call require_ok(HYPRE_ILUDestroy(solver%precond), 'HYPRE_ILUDestroy')
      end select
    end if
    solver%krylov = c_null_ptr
    solver%precond = c_null_ptr
    solver%set_up = .false.
  end subroutine destroy_krylov

  !> Fortran view of the local entries of a HYPRE_ParVector (no copy; hypre_comm_c.c says why).
  function local_view(vector) result(local)
    type(c_ptr), intent(in) :: vector
    real(c_double), pointer, contiguous :: local(:)
    integer(c_int) :: n
    type(c_ptr) :: data
    data = agglo_hypre_par_vector_local_data(vector, n)
    call c_f_pointer(data, local, [n])
  end function local_view

  !> hypre's preconditioner callback (HYPRE_PtrToParSolverFcn): correction = M^{-1} residual.
  !> hypre passes back the "solver" given to SetPrecond, here the handle to the caller's object.
  !> The signature is hypre's; the matrix is not needed (the caller's object knows its operator).
  integer(c_int) function apply_user_preconditioner(handle_pointer, matrix, residual, correction) &
      bind(C, name='agglo_hypre_apply_user_preconditioner')
    type(c_ptr), value :: handle_pointer, matrix, residual, correction
    type(user_handle_t), pointer :: handle
    real(c_double), pointer, contiguous :: residual_local(:), correction_local(:)
    call c_f_pointer(handle_pointer, handle)
    residual_local => local_view(residual)
    correction_local => local_view(correction)
    call handle%user%apply(residual_local, correction_local)
    apply_user_preconditioner = 0
  end function apply_user_preconditioner

  !> The setup callback: the caller's preconditioner is ready when it is handed over (hypre's
  !> signature; no argument is needed).
  integer(c_int) function set_up_user_preconditioner(handle_pointer, matrix, rhs, solution) &
      bind(C, name='agglo_hypre_set_up_user_preconditioner')
    type(c_ptr), value :: handle_pointer, matrix, rhs, solution
    set_up_user_preconditioner = 0
  end function set_up_user_preconditioner

  !> The error code of a Krylov solve with the non-convergence bit removed. Not converging is an
  !> outcome, not an error (the status reports it): hypre raises HYPRE_ERROR_CONV in its global
  !> error flag, which every later call returns until it is cleared (reference manual, "Error
  !> handling"), so it is cleared at once.
  integer(c_int) function accept_non_convergence(ierr)
    integer(c_int), intent(in) :: ierr
    accept_non_convergence = ierr
    if (iand(ierr, hypre_error_conv) /= 0) then
      accept_non_convergence = ierr - hypre_error_conv
      call require_ok(HYPRE_ClearAllErrors(), 'HYPRE_ClearAllErrors')
    end if
  end function accept_non_convergence

  !> Any hypre error other than non-convergence is a defect or a resource failure: stop.
  subroutine require_ok(ierr, call_name)
    integer(c_int), intent(in) :: ierr
    character(len=*), intent(in) :: call_name
    character(len=160) :: text
    if (ierr == 0) return
    write(text, '(a,i0,a)') 'hypre: '//call_name//' returned error code ', ierr, ' (HYPRE_utilities.h lists the bits)'
    call fatal(trim(text), collective=.false.)
  end subroutine require_ok
end module hypre_solver
