!> The Crank-Nicolson momentum predictor with the immersed-boundary rows, solved with hypre
!> (docs/theory.md, "Linear solver (hypre)": the implicit coupling with Crank-Nicolson).
!>
!> Each velocity component c of the predictor satisfies, on its own staggered nodes,
!>   fluid node:     (I - alpha L_h) u* = b                           (the Helmholtz row, alpha = nu dt / 2)
!>   ghost node G:   (1 + kappa w_G) u_G + kappa sum_{j /= G} w_j u_j = (1 + kappa) u_B   (Eq. 7)
!>   interior node:  u = u_rigid(node)
!> with b the right-hand side fluid_predict assembles, u_B = U + Omega x r at the ghost's surface
!> point and the stencil, weights and kappa of immersed_geometry (pure mirror, kappa = 1, for the
!> implicit coupling; the 1.5-cell image point, kappa <= 1, for the explicit one). The ghost rows'
!> stencils may hold fluid nodes, so the whole system is solved at once: replacing the rows of an
!> FFT Crank-Nicolson solution afterwards would not reach this fixed point (docs/theory.md).
!>
!> The system is non-symmetric (the ghost rows); it is solved per component. By default (method
!> 'capacitance') by GMRES on the ghost rows only, one FFT Helmholtz solve per iteration and no
!> matrix (immersed_capacitance; docs/studies/performance.md, "Crank-Nicolson with two bodies at
!> 128^3"). The reference (method 'hypre') is a hypre Krylov method on the whole system
!> (hypre_solver), BiCGSTAB preconditioned by the FFT Helmholtz solve with a Jacobi correction on
!> the replaced rows (hypre_fft_preconditioner), as follows. The right-hand side
!> is set every step. After a classification (bodies moved) only the body rows are assembled again
!> and compared with the last matrix's: when every ghost and interior node kept its status and
!> every ghost row its stencil nodes (a sub-cell move), their new values are written into the
!> matrix in place (the fluid rows, (I - alpha L_h), have not changed); otherwise the matrix of the
!> new pattern is built (full_builds counts these, per component), in one pass over the Helmholtz
!> rows with the body rows in their place; a new alpha (a new dt) builds it again likewise. The
!> Krylov solver and its vectors are set up once per component and kept across steps and matrices.
!>
!> Loads: the momentum the body rows add is what the momentum-balance loads of immersed_loads
!> need. Summed over the periodic box, sum (I - alpha L_h) u = sum u, so the system adds to the
!> fluid rho dV sum_nodes (u* - b) = rho dV sum_{ghost, interior} [(I - alpha L_h) u* - b]: each
!> ghost and interior node adds its Helmholtz-row residual, as if its value had been imposed on
!> the value (I - alpha L_h) u* = b would have given it. That change goes to the step's bookkeeping
!> (immersed_loads account), so the box's momentum budget closes as with explicit diffusion.
module immersed_predictor
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_LOGICAL, MPI_LAND
  use parallel_env, only: world, global_max
  use text_format, only: int_text
  use wall_clock, only: wall_time
  use fluid_grid, only: fluid_grid_t, allocate_field
  use halo_exchange, only: exchange_slab_halos
  use poisson_fft, only: poisson_fft_t, poisson_create
  use predictor_solver, only: predictor_solver_t, apply_predictor_operator
  use timer_registry, only: timer_register, timer_tic, timer_toc
  use hypre_solver, only: sparse_rows_t, linear_solver_config_t, linear_solver_t, solve_status_t, &
                          linear_solver_create, linear_solver_update_values, linear_solver_replace_matrix, &
                          linear_solver_solve, linear_solver_destroy, rows_local_count
  use hypre_helmholtz_rows, only: global_row, helmholtz_rows_create, helmholtz_rows_set_coefficient, field_to_rows, &
                                  rows_to_field
  use hypre_fft_preconditioner, only: fft_helmholtz_preconditioner_t, fft_preconditioner_create
  use immersed_geometry, only: ghost_node_t
  use immersed_nodes, only: ghost_row_diagonal
  use immersed_boundary, only: immersed_boundary_t, imposition_report_t, rigid_velocity, ghost_surface_value
  use immersed_loads, only: account
  use immersed_capacitance, only: capacitance_work_t, capacitance_result_t, capacitance_solve, capacitance_first_guess
  implicit none
  private
  public :: immersed_predictor_t, immersed_predictor_create, immersed_predictor_reclassified, &
            immersed_predictor_first_guess, default_predictor_config

  character(len=*), parameter :: component_names(3) = ['u', 'v', 'w']

  !> The system of one velocity component.
  type :: component_system_t
    !> The ghost and interior rows of the matrix, in ascending local row order, in compact CSR form
    !> (the entries of local row body_rows(s) are body%row_start(s) .. body%row_start(s + 1) - 1).
    integer, allocatable :: body_rows(:)
    type(sparse_rows_t) :: body
    type(linear_solver_t) :: solver
    logical :: created = .false.                              !< solver holds a matrix
    type(fft_helmholtz_preconditioner_t), pointer :: preconditioner => null()   !< heap: hypre keeps its address
    integer, allocatable :: ghost_rows(:), interior_rows(:)   !< local rows of the ghost and interior nodes
    real(wp), allocatable :: rhs(:), solution(:)              !< this rank's rows
    real(wp), allocatable :: guess(:)                         !< the Krylov solve's first guess (u^n)
    real(wp), allocatable :: b_ghost(:), b_interior(:)        !< b of fluid_predict at those rows
    real(wp), allocatable :: forcing(:)                       !< the ghost forcing z (method 'capacitance')
  end type component_system_t

  type, extends(predictor_solver_t) :: immersed_predictor_t
    !> The bodies, their classification and velocities at t^{n+1}; the caller points it at its
    !> immersed boundary before each fluid_predict (the predictor adds the rows' momentum to it).
    type(immersed_boundary_t), pointer :: ibm => null()
    type(linear_solver_config_t) :: config
    !> 'capacitance': GMRES on the ghost rows with the FFT Helmholtz solve (immersed_capacitance,
    !> the measured choice); 'hypre': the whole system with hypre (config), as a reference
    character(len=16) :: method = 'capacitance'
    type(fft_helmholtz_preconditioner_t) :: inverse   !< H^{-1}, the FFT solve the capacitance method uses
    type(capacitance_work_t) :: reduced               !< its work arrays (the components solve in turn)
    type(component_system_t) :: system(3)
    type(sparse_rows_t) :: helmholtz                  !< (I - alpha L_h) on every row, for the current alpha
    type(fluid_grid_t), pointer :: grid => null()     !< a copy of the fluid grid (heap) for the preconditioner
    type(poisson_fft_t), pointer :: fft => null()     !< the preconditioner's own FFT (heap)
    real(wp), allocatable :: work(:, :, :)            !< (I - alpha L_h) u* for the loads
    real(wp) :: alpha = -1                            !< nu dt / 2 the matrices hold
    logical :: stale = .true.                         !< the matrices predate the last classification
    logical :: has_guess = .false.                    !< system(:)%guess holds this step's first guess
    logical :: reuse_structure = .true.               !< replace only the values when the structure stands
    type(imposition_report_t) :: report               !< the last solve: sweeps = most iterations of a
                                                      !< component, residual = largest relative residual
    real(wp) :: build_seconds = 0, solve_seconds = 0  !< wall time of building and solving, summed
    integer :: builds = 0                             !< matrices built (after a classification)
    integer :: updates = 0                            !< of those (per component), values only (same structure)
    integer :: full_builds = 0                        !< component matrices built with a new pattern
    integer :: fft_solves = 0                         !< FFT Helmholtz solves of the capacitance method, summed
    integer :: preconditioner_iterations = 0          !< its preconditioner's GMRES iterations, summed
  contains
    procedure :: solve => immersed_predictor_solve
  end type immersed_predictor_t

contains

  !> BiCGSTAB with the FFT Helmholtz preconditioner (the measured choice, docs/studies/performance.md).
  pure function default_predictor_config(tolerance, max_iterations) result(config)
    real(wp), intent(in) :: tolerance
    integer, intent(in) :: max_iterations
    type(linear_solver_config_t) :: config
    config%method = 'bicgstab'
    config%preconditioner = 'user'
    config%tolerance = tolerance
    config%max_iterations = max_iterations
  end function default_predictor_config

  !> Prepare the predictor for the fluid grid (collective: the preconditioner's FFT plans).
  !> config%preconditioner = 'user' means the FFT Helmholtz preconditioner.
  subroutine immersed_predictor_create(predictor, grid, config)
    type(immersed_predictor_t), intent(inout) :: predictor
    type(fluid_grid_t), intent(in) :: grid
    type(linear_solver_config_t), intent(in) :: config
    integer :: c
    predictor%config = config
    ! The breakdown's order: the solves (one of the two methods), the FFT solves within them, then
    ! the matrices (the reference method's); timers never started are not listed.
    c = timer_register('hypre')
    c = timer_register('ghost-row GMRES')
    c = timer_register('  FFT preconditioner')
    c = timer_register('  capacitance matrix')
    c = timer_register('  capacitance solves')
    c = timer_register('hypre matrices')
    if (.not. associated(predictor%grid)) allocate(predictor%grid, predictor%fft)
    predictor%grid = grid
    call poisson_create(predictor%fft, predictor%grid, 'estimate')
    call fft_preconditioner_create(predictor%inverse, predictor%grid, predictor%fft, 1.0_wp)
    call allocate_field(grid, predictor%work)
    do c = 1, 3
      if (predictor%system(c)%created) call linear_solver_destroy(predictor%system(c)%solver)
      predictor%system(c)%created = .false.
      if (allocated(predictor%system(c)%rhs)) deallocate(predictor%system(c)%rhs, predictor%system(c)%solution)
      if (allocated(predictor%system(c)%guess)) deallocate(predictor%system(c)%guess)
      allocate(predictor%system(c)%guess(grid%nx * grid%ny * grid%nz_local))
    end do
    predictor%has_guess = .false.
    predictor%stale = .true.
    predictor%alpha = -1
  end subroutine immersed_predictor_create

  !> The nodes were classified again (the bodies moved): the next solve builds new matrices.
  subroutine immersed_predictor_reclassified(predictor)
    type(immersed_predictor_t), intent(inout) :: predictor
    predictor%stale = .true.
  end subroutine immersed_predictor_reclassified

  !> The first guess of the next solve: u^n (near a steady state u* differs from u^n by far less
  !> than from b, which lacks alpha L u*; measured in docs/studies/performance.md). Without it the solve
  !> starts from b with the body rows' values.
  subroutine immersed_predictor_first_guess(predictor, grid, u, v, w)
    type(immersed_predictor_t), intent(inout) :: predictor
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    call field_to_rows(grid, u, predictor%system(1)%guess)
    call field_to_rows(grid, v, predictor%system(2)%guess)
    call field_to_rows(grid, w, predictor%system(3)%guess)
    predictor%has_guess = .true.
  end subroutine immersed_predictor_first_guess

  !> A u* = b with the body rows (collective). On entry u, v, w hold b, on exit u* (interiors;
  !> halos current). The momentum of the body rows goes to predictor%ibm's load bookkeeping.
  !> poisson is not used: hypre calls the preconditioner through an address it keeps between
  !> steps, so the preconditioner has its own FFT (predictor%fft).
  subroutine immersed_predictor_solve(self, grid, poisson, alpha, u, v, w)
    class(immersed_predictor_t), intent(inout) :: self
    type(fluid_grid_t), intent(inout) :: grid
    type(poisson_fft_t), intent(inout) :: poisson
    real(wp), intent(in) :: alpha
    real(wp), intent(inout) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp) :: t0, scale
    integer :: c
    if (.not. associated(self%ibm)) call fatal('immersed predictor: no immersed boundary given')
    if (.not. (alpha > 0.0_wp)) call fatal('immersed predictor: needs the Crank-Nicolson predictor (alpha > 0)')
    t0 = wall_time()
    if (self%method == 'capacitance') then
      ! Only the lists of the body rows: no matrix (immersed_capacitance).
      if (self%stale) then
        do c = 1, 3
          call assemble_row_lists(self, grid, c)
        end do
        self%builds = self%builds + 1
      end if
      self%inverse%coefficient = alpha
    else if (alpha /= self%alpha) then
      if (allocated(self%helmholtz%row_start)) then
        call helmholtz_rows_set_coefficient(grid, alpha, self%helmholtz)
      else
        call helmholtz_rows_create(grid, alpha, self%helmholtz)
      end if
    end if
    if (self%method == 'capacitance') then
      continue
    else if (self%stale) then
      do c = 1, 3
        call build_system(self, grid, c, alpha)
      end do
      self%builds = self%builds + 1
    else if (alpha /= self%alpha) then
      do c = 1, 3
        call helmholtz_values(self, c, alpha)
      end do
    end if
    self%alpha = alpha
    self%stale = .false.
    self%build_seconds = self%build_seconds + wall_time() - t0

    t0 = wall_time()
    self%report = imposition_report_t()
    scale = 0
    call solve_component(self, grid, 1, u, scale)
    call solve_component(self, grid, 2, v, scale)
    call solve_component(self, grid, 3, w, scale)
    self%report%velocity_scale = max(global_max(scale), tiny(1.0_wp))
    call exchange_slab_halos(grid%slab, u, v, w)
    call account_rows(self, grid, 1, alpha, u)
    call account_rows(self, grid, 2, alpha, v)
    call account_rows(self, grid, 3, alpha, w)
    self%report%largest_change = global_max(self%report%largest_change) / self%report%velocity_scale
    self%has_guess = .false.
    self%solve_seconds = self%solve_seconds + wall_time() - t0
  end subroutine immersed_predictor_solve

  !> The rows of component c for the current classification, and its hypre solver (collective).
  !> When the new body rows have the old ones' pattern (the same ghost and interior nodes, the same
  !> stencil nodes: a body moved by a fraction of a cell without changing any node's status) and
  !> alpha is the matrix's, only the body rows' values are written into the matrix; otherwise the
  !> matrix is built from the Helmholtz rows with the body rows in place of theirs (the solver
  !> created the first time).
  subroutine build_system(self, grid, c, alpha)
    type(immersed_predictor_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c
    real(wp), intent(in) :: alpha
    integer, allocatable :: old_rows(:), old_start(:), old_columns(:)
    logical :: same_structure
    integer :: g, m
    associate (sys => self%system(c))
      if (allocated(sys%body_rows)) then
        call move_alloc(sys%body_rows, old_rows)
        call move_alloc(sys%body%row_start, old_start)
        call move_alloc(sys%body%columns, old_columns)
      end if
      call assemble_body_rows(self, grid, c)
      same_structure = .false.
      if (sys%created .and. allocated(old_rows) .and. self%reuse_structure) then
        same_structure = size(old_rows) == size(sys%body_rows)
        if (same_structure) same_structure = all(old_rows == sys%body_rows)
        if (same_structure) same_structure = all(old_start == sys%body%row_start)
        if (same_structure) same_structure = all(old_columns == sys%body%columns)
      end if
      ! Every rank must take the same branch (building is collective).
      same_structure = global_all(same_structure)
    end associate
    associate (sys => self%system(c), nodes => self%ibm%geometry%component(c))
      if (.not. associated(sys%preconditioner)) allocate(sys%preconditioner)
      if (.not. associated(sys%preconditioner%grid)) &
          call fft_preconditioner_create(sys%preconditioner, self%grid, self%fft, alpha)
      if (.not. allocated(sys%solution)) allocate(sys%solution(rows_local_count(self%helmholtz)))
      sys%preconditioner%coefficient = alpha
      sys%preconditioner%replaced_rows = [sys%ghost_rows, sys%interior_rows]
      sys%preconditioner%replaced_diagonal = [(ghost_row_diagonal(nodes%ghost(g)), g = 1, nodes%n_ghost), &
                                               (1.0_wp, m = 1, nodes%n_interior)]
      if (same_structure .and. alpha == self%alpha) then
        ! The fluid rows keep their values: only the body rows get theirs, in place.
        call linear_solver_update_values(sys%solver, sys%body, sys%body_rows)
        self%updates = self%updates + 1
      else if (.not. sys%created) then
        if (self%config%preconditioner == 'user') then
          call linear_solver_create(sys%solver, self%helmholtz, self%config, sys%preconditioner, &
                                    replaced=sys%body, replaced_rows=sys%body_rows)
        else
          call linear_solver_create(sys%solver, self%helmholtz, self%config, replaced=sys%body, &
                                    replaced_rows=sys%body_rows)
        end if
        sys%created = .true.
        self%full_builds = self%full_builds + 1
      else
        ! A new pattern (or a new dt as well: every row has new values, built afresh in one pass).
        call linear_solver_replace_matrix(sys%solver, self%helmholtz, sys%body, sys%body_rows)
        self%full_builds = self%full_builds + 1
      end if
    end associate
  end subroutine build_system

  !> True on every rank when flag is true on every rank (collective).
  logical function global_all(flag)
    logical, intent(in) :: flag
    global_all = flag
    call MPI_Allreduce(MPI_IN_PLACE, global_all, 1, MPI_LOGICAL, MPI_LAND, world)
  end function global_all

  !> New Helmholtz values (a new dt) on the same structure (the body rows do not depend on dt):
  !> the matrix is built again in one pass over the rows (as cheap as writing every value anew).
  subroutine helmholtz_values(self, c, alpha)
    type(immersed_predictor_t), intent(inout) :: self
    integer, intent(in) :: c
    real(wp), intent(in) :: alpha
    self%system(c)%preconditioner%coefficient = alpha
    call linear_solver_replace_matrix(self%system(c)%solver, self%helmholtz, self%system(c)%body, &
                                      self%system(c)%body_rows)
  end subroutine helmholtz_values

  !> The local rows of component c's ghost and interior nodes in the classification's order, and
  !> in_list (optional): for each local row g > 0 for the g-th ghost, -m for the m-th interior node,
  !> 0 for a fluid row. Also sizes the right-hand side, solution and b arrays of the body rows.
  subroutine assemble_row_lists(self, grid, c, in_list)
    type(immersed_predictor_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c
    integer, allocatable, intent(out), optional :: in_list(:)
    integer :: n_local, g, m
    n_local = grid%nx * grid%ny * grid%nz_local
    associate (nodes => self%ibm%geometry%component(c), sys => self%system(c))
      if (allocated(sys%ghost_rows)) deallocate(sys%ghost_rows, sys%interior_rows, sys%b_ghost, sys%b_interior)
      allocate(sys%ghost_rows(nodes%n_ghost), sys%interior_rows(nodes%n_interior))
      allocate(sys%b_ghost(nodes%n_ghost), sys%b_interior(nodes%n_interior))
      if (.not. allocated(sys%rhs)) allocate(sys%rhs(n_local))
      if (present(in_list)) allocate(in_list(n_local), source=0)
      do g = 1, nodes%n_ghost
        sys%ghost_rows(g) = local_row(grid, nodes%ghost(g)%node)
        if (present(in_list)) in_list(sys%ghost_rows(g)) = g
      end do
      do m = 1, nodes%n_interior
        sys%interior_rows(m) = local_row(grid, nodes%interior(:, m))
        if (present(in_list)) in_list(sys%interior_rows(m)) = -m
      end do
    end associate
  end subroutine assemble_row_lists

  !> The body rows of component c (compact CSR, ascending local rows): the ghost row (G, then the
  !> stencil's other corners) and the identity row of each interior node; and the lists of the
  !> ghost and interior rows in the classification's order.
  subroutine assemble_body_rows(self, grid, c)
    type(immersed_predictor_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c
    integer, allocatable :: in_list(:)
    integer :: n_local, n_body, r, s, entry, corner

    n_local = grid%nx * grid%ny * grid%nz_local
    call assemble_row_lists(self, grid, c, in_list)
    associate (nodes => self%ibm%geometry%component(c), sys => self%system(c))
      n_body = nodes%n_ghost + nodes%n_interior
      sys%body_rows = pack([(r, r = 1, n_local)], in_list /= 0)
      if (size(sys%body_rows) /= n_body) call fatal('immersed predictor: two ghost or interior records on one '// &
                                                    'node (the classification owns each node once)', collective=.false.)
      if (allocated(sys%body%row_start)) deallocate(sys%body%row_start)
      if (allocated(sys%body%columns)) deallocate(sys%body%columns)
      if (allocated(sys%body%values)) deallocate(sys%body%values)
      allocate(sys%body%row_start(n_body + 1), sys%body%columns(9 * nodes%n_ghost + nodes%n_interior), &
               sys%body%values(9 * nodes%n_ghost + nodes%n_interior))
      sys%body%first_row = self%helmholtz%first_row
      sys%body%last_row = self%helmholtz%last_row
      entry = 0
      do s = 1, n_body
        r = sys%body_rows(s)
        sys%body%row_start(s) = entry + 1
        entry = entry + 1
        sys%body%columns(entry) = self%helmholtz%columns(self%helmholtz%row_start(r))   ! the diagonal
        if (in_list(r) > 0) then
          associate (ghost => nodes%ghost(in_list(r)))
            sys%body%values(entry) = ghost_row_diagonal(ghost)
            do corner = 1, 8
              if (corner == ghost%self_corner) cycle
              entry = entry + 1
              sys%body%columns(entry) = global_row(grid, ghost%stencil(1, corner), ghost%stencil(2, corner), &
                                                   ghost%stencil(3, corner))
              sys%body%values(entry) = ghost%extrapolation * ghost%weight(corner)
            end do
          end associate
        else
          sys%body%values(entry) = 1.0_wp
        end if
      end do
      sys%body%row_start(n_body + 1) = entry + 1
      sys%body%columns = sys%body%columns(1:entry)
      sys%body%values = sys%body%values(1:entry)
    end associate
  end subroutine assemble_body_rows

  !> Solve component c: b from field, the body rows' right-hand sides, the Krylov solve from the
  !> first guess; u* back into field (interior). Stops the run if it does not converge.
  subroutine solve_component(self, grid, c, field, scale)
    type(immersed_predictor_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    real(wp), intent(inout) :: scale
    type(solve_status_t) :: status
    integer :: g, m
    character(len=400) :: text
    associate (sys => self%system(c), nodes => self%ibm%geometry%component(c), arms => self%ibm%arms(c))
      call field_to_rows(grid, field, sys%rhs)
      do g = 1, nodes%n_ghost
        sys%b_ghost(g) = sys%rhs(sys%ghost_rows(g))
        sys%rhs(sys%ghost_rows(g)) = (1.0_wp + nodes%ghost(g)%extrapolation) * ghost_surface_value(self%ibm, c, g)
        scale = max(scale, abs(sys%rhs(sys%ghost_rows(g))))
      end do
      do m = 1, nodes%n_interior
        sys%b_interior(m) = sys%rhs(sys%interior_rows(m))
        sys%rhs(sys%interior_rows(m)) = rigid_velocity(self%ibm, nodes%interior_body(m), c, arms%interior(:, m))
        scale = max(scale, abs(sys%rhs(sys%interior_rows(m))))
      end do
      if (self%method == 'capacitance') then
        call solve_reduced(self, grid, c, status)
      else
        if (self%has_guess) then
          sys%solution = sys%guess
        else
          sys%solution = sys%rhs
        end if
        call linear_solver_solve(sys%solver, sys%rhs, sys%solution, status)
      end if
      if (.not. status%converged) then
        write(text, '(a,i0,a,es10.3,a,es10.3,a)') 'immersed predictor: the Crank-Nicolson system of '// &
            component_names(c)//' with the immersed-boundary rows did not converge in ', status%iterations, &
            ' iterations (relative residual ', status%relative_residual, ' > tolerance ', status%tolerance, &
            '); use a smaller &run dt (or cfl_target), a looser &fluid predictor_tolerance or a larger '// &
            '&fluid predictor_max_iterations (now '//int_text(status%max_iterations)//')'
        call fatal(trim(text))
      end if
      self%report%sweeps = max(self%report%sweeps, status%iterations)
      self%report%residual = max(self%report%residual, status%relative_residual)
      call rows_to_field(grid, sys%solution, field)
    end associate
  end subroutine solve_component

  !> Component c's system by GMRES on its ghost rows (immersed_capacitance), from the ghost forcing
  !> of u^n when the caller gave it (immersed_predictor_first_guess), else from 0 (collective).
  subroutine solve_reduced(self, grid, c, status)
    type(immersed_predictor_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c
    type(solve_status_t), intent(out) :: status
    type(capacitance_result_t) :: result
    call timer_tic('ghost-row GMRES')
    associate (sys => self%system(c), nodes => self%ibm%geometry%component(c))
      if (.not. allocated(sys%solution)) allocate(sys%solution(size(sys%rhs)))
      if (allocated(sys%forcing)) then
        if (size(sys%forcing) /= nodes%n_ghost) deallocate(sys%forcing)
      end if
      if (.not. allocated(sys%forcing)) allocate(sys%forcing(nodes%n_ghost))
      if (self%has_guess) then
        sys%solution = sys%guess
        sys%solution(sys%interior_rows) = sys%rhs(sys%interior_rows)
        call capacitance_first_guess(self%reduced, grid, nodes, self%ibm%planes%halo_planes, self%inverse%coefficient, &
                                     sys%solution, sys%rhs(sys%ghost_rows), sys%forcing)
      else
        sys%forcing = 0
      end if
      call capacitance_solve(self%reduced, grid, nodes, sys%ghost_rows, sys%interior_rows, sys%rhs, &
                             self%ibm%planes%halo_planes, self%ibm%planes%stencils_leave_slab, self%inverse, &
                             self%config%tolerance, &
                             self%config%max_iterations, self%config%gmres_restart, sys%forcing, sys%solution, result)
    end associate
    status%converged = result%converged
    status%iterations = result%iterations
    status%relative_residual = result%relative_residual
    status%tolerance = self%config%tolerance
    status%max_iterations = self%config%max_iterations
    self%fft_solves = self%fft_solves + result%fft_solves
    self%preconditioner_iterations = self%preconditioner_iterations + result%inner_iterations
    call timer_toc('ghost-row GMRES')
  end subroutine solve_reduced

  !> The momentum each ghost and interior node of component c adds (module header): its
  !> Helmholtz-row residual (I - alpha L_h) u* - b, to the load bookkeeping. field's halos current.
  subroutine account_rows(self, grid, c, alpha, field)
    type(immersed_predictor_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c
    real(wp), intent(in) :: alpha
    real(wp), intent(in), contiguous :: field(0:, 0:, 0:)
    real(wp) :: delta
    integer :: g, m, node(3)
    call apply_predictor_operator(grid, alpha, field, self%work)
    associate (sys => self%system(c), nodes => self%ibm%geometry%component(c), arms => self%ibm%arms(c))
      do g = 1, nodes%n_ghost
        node = nodes%ghost(g)%node
        delta = self%work(node(1), node(2), node(3)) - sys%b_ghost(g)
        call account(self%ibm, grid, nodes%ghost(g)%body, c, arms%ghost(:, g), delta)
        self%report%largest_change = max(self%report%largest_change, abs(delta))
      end do
      do m = 1, nodes%n_interior
        node = nodes%interior(:, m)
        delta = self%work(node(1), node(2), node(3)) - sys%b_interior(m)
        call account(self%ibm, grid, nodes%interior_body(m), c, arms%interior(:, m), delta)
        self%report%largest_change = max(self%report%largest_change, abs(delta))
      end do
    end associate
  end subroutine account_rows

  !> Local row (1-based, in field_to_rows order) of node (i, j global, k local to the slab).
  integer function local_row(grid, node)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: node(3)
    if (node(3) < 1 .or. node(3) > grid%nz_local) call fatal('immersed predictor: a body node outside the slab', &
                                                             collective=.false.)
    local_row = node(1) + grid%nx * ((node(2) - 1) + grid%ny * (node(3) - 1))
  end function local_row
end module immersed_predictor
