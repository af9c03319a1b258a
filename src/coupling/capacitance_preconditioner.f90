!> A sparse approximation of the capacitance matrix C = A_G H^{-1} P_G^T (immersed_capacitance),
!> solved approximately on each rank as the preconditioner of the reduced system's GMRES.
!>
!> H = I - alpha L_h on the periodic grid is translation invariant, so H^{-1} P_G^T z is the
!> superposition of one discrete Green's function g = H^{-1} e_0 placed at the ghost nodes, and
!>     C_{GH} = sum_{a in S(G)} A_{Ga} g(x_a - x_H),
!> S(G) the nodes of G's row that are not interior (G itself and its image point's trilinear
!> corners). g decays geometrically away from its centre (by a factor of about 0.23 per cell at
!> nu dt/dx^2 = 0.4, the root of the one-dimensional recurrence), so keeping the offsets within a
!> window of a few cells in each direction gives a sparse matrix C~ close to C, with no FFT:
!> g itself costs one FFT Helmholtz solve whenever alpha changes (once per run at a fixed dt). The
!> capacitance-matrix idea of Buzbee, Dorr, George & Golub (1971, SIAM J. Numer. Anal. 8, 722)
!> with C formed explicitly, here truncated; the preconditioner keeps only the couplings among the
!> ghost nodes of one rank (block Jacobi over the slabs: no communication), and its system is
!> solved by a few GMRES iterations on the rank's rows with C~'s diagonal as right preconditioner.
!> The outer GMRES is flexible (the inner solve is not a fixed linear map), and its stopping rule
!> is on the true residual: the preconditioner changes the iterations, not the answer.
module capacitance_preconditioner
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp
  use fluid_grid, only: fluid_grid_t
  use immersed_nodes, only: component_nodes_t, node_interior, ghost_row_diagonal
  use hypre_fft_preconditioner, only: fft_helmholtz_preconditioner_t
  use gmres_cycle, only: gmres_cycle_t, gmres_prepare, gmres_begin, gmres_orthogonalise, gmres_coefficients
  implicit none
  private
  public :: local_capacitance_t, local_capacitance_green, local_capacitance_assemble, local_capacitance_solve

  !> The window: at most 4 cells each way (the matrix's cost grows as its cube; at nu dt/dx^2 = 0.4
  !> the reduced solve takes 2 iterations with 4 cells, 3 with 3, 4 with 2 (docs/performance.md)),
  !> and no wider than g needs: the offsets along an axis beyond it hold less than 1e-4 of g(0).
  integer, parameter :: largest_window = 4
  real(wp), parameter :: window_cutoff = 1.0e-4_wp

  type :: local_capacitance_t
    integer :: inner_iterations = 40            !< GMRES iterations of one application at most
    real(wp) :: inner_tolerance = 1.0e-6_wp     !< relative residual of one application
    real(wp) :: alpha = -1                      !< the coefficient g was computed for
    integer :: reach(3) = 0                     !< the window: offsets kept per direction (cells)
    real(wp), allocatable :: green(:, :, :)     !< g(dx, dy, dz), |d_i| <= reach(i) at least
    !> global index i + d (i in 1..n, |d| <= reach) wrapped into 1..n, in y and z (no modulo per entry)
    integer, allocatable :: wrap_y(:), wrap_z(:)
    !> this rank's ghost nodes by x-line (j, k): line_start(j + ny (k - 1)) .. line_start(next) - 1
    !> index line_x (their i, ascending) and line_ghost (their ghost index)
    integer, allocatable :: line_start(:), line_x(:), line_ghost(:)
    integer, allocatable :: row_start(:)        !< (n_ghost + 1) compressed rows of C~
    integer, allocatable :: column(:)
    real(wp), allocatable :: entry(:)
    real(wp), allocatable :: diagonal(:)        !< C~'s diagonal (the inner right preconditioner)
    real(wp), allocatable :: accumulated(:)     !< (n_ghost) one row of C~ while it is summed
    integer, allocatable :: touched(:)          !< its columns so far
    logical, allocatable :: listed(:)           !< (n_ghost) the column is in touched
    type(gmres_cycle_t) :: inner
    integer :: inner_total = 0                  !< inner iterations, summed (diagnostics)
  end type local_capacitance_t

contains

  !> g = H^{-1} e_0 near its centre, from one FFT Helmholtz solve (collective), and the window, when
  !> the coefficient of fft differs from the last one (the same on every rank: a restart
  !> recomputes the same g).
  subroutine local_capacitance_green(self, grid, fft, n_rows)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    type(fft_helmholtz_preconditioner_t), intent(inout) :: fft
    integer, intent(in) :: n_rows
    real(wp), allocatable :: delta(:), image(:)
    integer :: extent(3), di, dj, dk, k, d, w
    if (allocated(self%green) .and. fft%coefficient == self%alpha) return
    ! One offset beyond the largest window (to choose the window below), and no offset that
    ! wraps onto another across the periodic box.
    extent = min(largest_window + 1, ([grid%nx, grid%ny, grid%nz] - 1) / 2)
    if (allocated(self%green)) deallocate(self%green)
    allocate(self%green(-extent(1):extent(1), -extent(2):extent(2), -extent(3):extent(3)))
    allocate(delta(n_rows), image(n_rows))
    delta = 0
    if (grid%z_offset == 0) delta(1) = 1     ! node (1, 1, 1)
    call fft%apply(delta, image)
    self%green = 0
    do dk = -extent(3), extent(3)
      k = modulo(dk, grid%nz) + 1 - grid%z_offset
      if (k < 1 .or. k > grid%nz_local) cycle
      do dj = -extent(2), extent(2)
        do di = -extent(1), extent(1)
          self%green(di, dj, dk) = image(modulo(di, grid%nx) + 1 + grid%nx * (modulo(dj, grid%ny) + grid%ny * (k - 1)))
        end do
      end do
    end do
    call MPI_Allreduce(MPI_IN_PLACE, self%green, size(self%green), mpi_wp, MPI_SUM, world)
    self%alpha = fft%coefficient
    ! The window per direction: the smallest that leaves out no axis offset where g exceeds
    ! window_cutoff g(0) (g decays slowest along the axes), at most largest_window.
    do d = 1, 3
      self%reach(d) = min(largest_window, extent(d))
      do w = 1, min(largest_window, extent(d) - 1)
        if (axis_value(d, w + 1) <= window_cutoff * self%green(0, 0, 0)) then
          self%reach(d) = w
          exit
        end if
      end do
    end do
    call wrapped(grid%ny, self%reach(2), self%wrap_y)
    call wrapped(grid%nz, self%reach(3), self%wrap_z)
  contains
    real(wp) function axis_value(direction, offset)
      integer, intent(in) :: direction, offset
      integer :: at(3)
      at = 0
      at(direction) = offset
      axis_value = abs(self%green(at(1), at(2), at(3)))
    end function axis_value

    subroutine wrapped(n, reach, table)
      integer, intent(in) :: n, reach
      integer, allocatable, intent(inout) :: table(:)
      integer :: i
      if (allocated(table)) deallocate(table)
      allocate(table(1 - reach:n + reach))
      table = [(modulo(i - 1, n) + 1, i = 1 - reach, n + reach)]
    end subroutine wrapped
  end subroutine local_capacitance_green

  !> C~ on this rank's ghost nodes.
  subroutine local_capacitance_assemble(self, grid, nodes)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer :: g, corner, position, n_touched, n_entries, capacity
    real(wp) :: coefficient
    integer :: node(3)

    call prepare(self, nodes%n_ghost)
    call sort_into_lines(self, grid, nodes)
    n_entries = 0
    self%accumulated = 0
    self%listed = .false.
    do g = 1, nodes%n_ghost
      n_touched = 0
      associate (ghost => nodes%ghost(g))
        ! The ghost node itself (the row's diagonal coefficient 1 + kappa w_G), then the other corners.
        node = [ghost%node(1), ghost%node(2), ghost%node(3) + grid%z_offset]
        call add_term(node, ghost_row_diagonal(ghost))
        do corner = 1, 8
          if (corner == ghost%self_corner .or. ghost%stencil_status(corner) == node_interior) cycle
          coefficient = ghost%extrapolation * ghost%weight(corner)
          if (coefficient == 0.0_wp) cycle
          call add_term(ghost%stencil(:, corner), coefficient)
        end do
      end associate
      capacity = size(self%column)
      if (n_entries + n_touched > capacity) call grow(self, max(2 * capacity, n_entries + n_touched))
      self%column(n_entries + 1:n_entries + n_touched) = self%touched(1:n_touched)
      self%entry(n_entries + 1:n_entries + n_touched) = self%accumulated(self%touched(1:n_touched))
      self%accumulated(self%touched(1:n_touched)) = 0
      self%listed(self%touched(1:n_touched)) = .false.
      n_entries = n_entries + n_touched
      self%row_start(g + 1) = n_entries + 1
      self%diagonal(g) = 0
      do position = self%row_start(g), n_entries
        if (self%column(position) == g) self%diagonal(g) = self%entry(position)
      end do
      if (.not. (abs(self%diagonal(g)) > 0.0_wp)) self%diagonal(g) = 1.0_wp
    end do
  contains
    !> coefficient * g(x_a - x_H) into the row for every ghost node H of this rank within the window
    !> of node a (global i, j, k): the x-lines of the window, and along each the ghost nodes
    !> within reach of a (the window's x-range split where it wraps across the box).
    subroutine add_term(a, coefficient)
      integer, intent(in) :: a(3)
      real(wp), intent(in) :: coefficient
      integer :: dj, dk, k, line, lowest, highest
      lowest = a(1) - self%reach(1)
      highest = a(1) + self%reach(1)
      do dk = -self%reach(3), self%reach(3)
        k = self%wrap_z(a(3) + dk) - grid%z_offset
        if (k < 1 .or. k > grid%nz_local) cycle
        do dj = -self%reach(2), self%reach(2)
          line = self%wrap_y(a(2) + dj) + grid%ny * (k - 1)
          if (self%line_start(line) == self%line_start(line + 1)) cycle
          if (lowest < 1) then
            call add_along_line(a, coefficient, line, -dj, -dk, lowest + grid%nx, grid%nx)
            call add_along_line(a, coefficient, line, -dj, -dk, 1, highest)
          else if (highest > grid%nx) then
            call add_along_line(a, coefficient, line, -dj, -dk, lowest, grid%nx)
            call add_along_line(a, coefficient, line, -dj, -dk, 1, highest - grid%nx)
          else
            call add_along_line(a, coefficient, line, -dj, -dk, lowest, highest)
          end if
        end do
      end do
    end subroutine add_term

    !> The ghost nodes of x-line `line` with first <= i <= last (x_a - x_H = (-di, back_y, back_z)).
    subroutine add_along_line(a, coefficient, line, back_y, back_z, first, last)
      integer, intent(in) :: a(3), line, back_y, back_z, first, last
      real(wp), intent(in) :: coefficient
      integer :: position, low, high, h, di
      ! the first position with line_x >= first (bisection; the lists are short)
      low = self%line_start(line)
      high = self%line_start(line + 1)
      do while (low < high)
        position = (low + high) / 2
        if (self%line_x(position) < first) then
          low = position + 1
        else
          high = position
        end if
      end do
      do position = low, self%line_start(line + 1) - 1
        if (self%line_x(position) > last) exit
        h = self%line_ghost(position)
        di = modulo(self%line_x(position) - a(1) + self%reach(1), grid%nx) - self%reach(1)
        if (.not. self%listed(h)) then
          n_touched = n_touched + 1
          self%touched(n_touched) = h
          self%listed(h) = .true.
        end if
        ! g is even in each direction; the signs as in the formula
        self%accumulated(h) = self%accumulated(h) + coefficient * self%green(-di, back_y, back_z)
      end do
    end subroutine add_along_line
  end subroutine local_capacitance_assemble

  !> y ~ C~^{-1} r on this rank's ghost nodes: GMRES from y = 0 on C~ D^{-1} w = r, y = D^{-1} w,
  !> to inner_tolerance or inner_iterations (rank-local: no communication).
  subroutine local_capacitance_solve(self, r, y)
    type(local_capacitance_t), intent(inout) :: self
    real(wp), intent(in) :: r(:)
    real(wp), intent(out) :: y(:)
    real(wp) :: norm, estimate, coefficients(self%inner_iterations)
    logical :: breakdown
    integer :: j, n
    n = size(r)
    y = 0
    if (n == 0) return
    norm = norm2(r)
    if (.not. (norm > 0.0_wp)) return
    call gmres_prepare(self%inner, n, self%inner_iterations, collective=.false.)
    call gmres_begin(self%inner, r, norm)
    j = 0
    do while (j < self%inner_iterations)
      j = j + 1
      call sparse_product(self, self%inner%basis(:, j) / self%diagonal, self%inner%basis(:, j + 1))
      call gmres_orthogonalise(self%inner, j, estimate, breakdown)
      if (breakdown) then
        j = j - 1
        exit
      end if
      if (estimate <= self%inner_tolerance * norm) exit
    end do
    self%inner_total = self%inner_total + j
    if (j == 0) return
    call gmres_coefficients(self%inner, j, coefficients)
    y = matmul(self%inner%basis(:, 1:j), coefficients(1:j)) / self%diagonal
  end subroutine local_capacitance_solve

  !> This rank's ghost nodes by x-line, ascending in i along each (a counting sort by line, then
  !> insertion along the short lines).
  subroutine sort_into_lines(self, grid, nodes)
    type(local_capacitance_t), intent(inout) :: self
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: nodes
    integer, allocatable :: next(:)
    integer :: n_lines, g, line, position, i
    n_lines = grid%ny * grid%nz_local
    if (allocated(self%line_start)) then
      if (size(self%line_start) /= n_lines + 1) deallocate(self%line_start)
    end if
    if (.not. allocated(self%line_start)) allocate(self%line_start(n_lines + 1))
    if (allocated(self%line_x)) then
      if (size(self%line_x) /= nodes%n_ghost) deallocate(self%line_x, self%line_ghost)
    end if
    if (.not. allocated(self%line_x)) allocate(self%line_x(nodes%n_ghost), self%line_ghost(nodes%n_ghost))
    ! counts in line_start(line + 1), then their prefix sums: the lines' first positions
    self%line_start = 0
    do g = 1, nodes%n_ghost
      line = nodes%ghost(g)%node(2) + grid%ny * (nodes%ghost(g)%node(3) - 1)
      self%line_start(line + 1) = self%line_start(line + 1) + 1
    end do
    self%line_start(1) = 1
    do line = 1, n_lines
      self%line_start(line + 1) = self%line_start(line + 1) + self%line_start(line)
    end do
    next = self%line_start(1:n_lines)
    do g = 1, nodes%n_ghost
      line = nodes%ghost(g)%node(2) + grid%ny * (nodes%ghost(g)%node(3) - 1)
      i = nodes%ghost(g)%node(1)
      position = next(line)
      next(line) = position + 1
      do while (position > self%line_start(line))
        if (self%line_x(position - 1) <= i) exit
        self%line_x(position) = self%line_x(position - 1)
        self%line_ghost(position) = self%line_ghost(position - 1)
        position = position - 1
      end do
      self%line_x(position) = i
      self%line_ghost(position) = g
    end do
  end subroutine sort_into_lines

  subroutine sparse_product(self, x, product)
    type(local_capacitance_t), intent(in) :: self
    real(wp), intent(in) :: x(:)
    real(wp), intent(out) :: product(:)
    integer :: g
    do g = 1, size(x)
      product(g) = dot_product(self%entry(self%row_start(g):self%row_start(g + 1) - 1), &
                               x(self%column(self%row_start(g):self%row_start(g + 1) - 1)))
    end do
  end subroutine sparse_product

  subroutine prepare(self, n_ghost)
    type(local_capacitance_t), intent(inout) :: self
    integer, intent(in) :: n_ghost
    if (allocated(self%diagonal)) then
      if (size(self%diagonal) /= n_ghost) deallocate(self%diagonal, self%row_start, self%accumulated, self%touched, &
                                                     self%listed)
    end if
    if (.not. allocated(self%diagonal)) allocate(self%diagonal(n_ghost), self%row_start(n_ghost + 1), &
                                                 self%accumulated(n_ghost), self%touched(n_ghost), self%listed(n_ghost))
    if (.not. allocated(self%column)) allocate(self%column(max(1, 64 * n_ghost)), self%entry(max(1, 64 * n_ghost)))
    self%row_start(1) = 1
  end subroutine prepare

  subroutine grow(self, capacity)
    type(local_capacitance_t), intent(inout) :: self
    integer, intent(in) :: capacity
    integer, allocatable :: column(:)
    real(wp), allocatable :: entry(:)
    allocate(column(capacity), entry(capacity))
    column(1:size(self%column)) = self%column
    entry(1:size(self%entry)) = self%entry
    call move_alloc(column, self%column)
    call move_alloc(entry, self%entry)
  end subroutine grow
end module capacitance_preconditioner
