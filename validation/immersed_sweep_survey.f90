!> Convergence of the implicit ghost rows (Jacobi sweeps of the pure mirror, immersed_boundary) for
!> needles and disks of aspect 5 at random orientations and positions (the immersed-boundary
!> validation ladder, rung 2; docs/validation.md, "Immersed boundary").
!>
!> One body of a given volume-equivalent radius in a 1 mm box (0.1 mm: the disk is 4.4 cells thick
!> at 64^3, 17.5 at 256^3; the paper's 50 um: 2.2 and 8.8) with a random rigid motion (U and Omega a of order U0) in
!> a smooth field u = U0 cos(2 pi (x + 2y + 3z)/L + c) that the imposition starts from, the ghost
!> values included: the sweeps count how far the ghost rows are from that start, the first
!> imposition of a step being the worst case (later impositions start from the previous values).
!> Tolerance 1e-12 of the velocity scale, at most 100 sweeps (the run stops otherwise).
module immersed_sweep_survey
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use parallel_env, only: global_sum
  use wall_clock, only: wall_time
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use immersed_geometry, only: immersed_body_t, node_position, thin_dimension_cells
  use immersed_boundary, only: immersed_boundary_t, imposition_report_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  implicit none
  private
  public :: sweep_survey_t, run_sweep_survey

  type :: sweep_survey_t
    character(len=8) :: shape = 'needle'     !< 'needle' or 'disk' (aspect 5)
    integer :: cells = 64                    !< cells per edge of the 1 mm box
    integer :: placements = 4                !< random orientations and positions
    real(wp) :: radius = 0.1e-3_wp           !< m, volume-equivalent radius (the paper's: 50 um)
    integer(i8) :: seed = 2026_i8
    ! Results
    real(wp) :: thin_cells = 0               !< thinnest dimension of the body, cells
    integer :: max_sweeps = 0
    real(wp) :: mean_sweeps = 0
    real(wp) :: max_residual = 0             !< largest final residual / velocity scale
    real(wp) :: mean_ghosts = 0              !< ghost nodes (u, v and w together) per placement
    real(wp) :: classify_seconds = 0         !< per placement
    real(wp) :: impose_seconds = 0           !< per placement
  end type sweep_survey_t

  real(wp), parameter :: box = 1.0e-3_wp, speed = 1.0e-3_wp

contains

  !> Run the survey (collective).
  subroutine run_sweep_survey(survey)
    type(sweep_survey_t), intent(inout) :: survey
    type(fluid_grid_t) :: grid
    type(random_stream_t) :: stream
    type(immersed_boundary_t) :: ibm
    type(immersed_body_t) :: bodies(1)
    type(imposition_report_t) :: report
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)
    real(wp) :: velocity(3, 1), angular_velocity(3, 1), t0, t1, t2
    integer :: p, d

    call grid_create(grid, survey%cells, survey%cells, survey%cells, box, box, box)
    call allocate_field(grid, u); call allocate_field(grid, v); call allocate_field(grid, w)
    call stream_seed(stream, survey%seed, stream_id=7)
    bodies(1)%shape = make_spheroid(trim(survey%shape), survey%radius, 1000.0_wp)
    survey%thin_cells = thin_dimension_cells(bodies(1)%shape, grid)
    survey%max_sweeps = 0
    survey%mean_sweeps = 0
    survey%max_residual = 0
    survey%mean_ghosts = 0
    survey%classify_seconds = 0
    survey%impose_seconds = 0
    do p = 1, survey%placements
      bodies(1)%centre = [(stream_uniform(stream) * box, d = 1, 3)]
      bodies(1)%orientation = random_orientation(stream)
      velocity(:, 1) = [(speed * stream_normal(stream), d = 1, 3)]
      angular_velocity(:, 1) = [(speed / survey%radius * stream_normal(stream), d = 1, 3)]
      call smooth_field(grid, 1, u); call smooth_field(grid, 2, v); call smooth_field(grid, 3, w)
      ibm = immersed_boundary_t()
      ibm%settings%coupling = 'implicit'
      ibm%settings%tolerance = 1.0e-12_wp
      ibm%settings%max_sweeps = 100
      t0 = wall_time()
      call ibm_set_bodies(ibm, grid, bodies, velocity, angular_velocity, classify=.true.)
      t1 = wall_time()
      call ibm_impose(ibm, grid, u, v, w, report)
      t2 = wall_time()
      survey%classify_seconds = survey%classify_seconds + (t1 - t0) / survey%placements
      survey%impose_seconds = survey%impose_seconds + (t2 - t1) / survey%placements
      survey%max_sweeps = max(survey%max_sweeps, report%sweeps)
      survey%mean_sweeps = survey%mean_sweeps + real(report%sweeps, wp) / survey%placements
      survey%max_residual = max(survey%max_residual, report%residual)
      survey%mean_ghosts = survey%mean_ghosts + &
          global_sum(real(sum(ibm%geometry%component(:)%n_ghost), wp)) / survey%placements
    end do
  end subroutine run_sweep_survey

  !> u_c = U0 cos(2 pi (x + 2y + 3z)/L + c) at every node of component c, halos included.
  subroutine smooth_field(grid, c, field)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, k
    real(wp) :: x(3)
    do k = 0, grid%nz_local + 1
      do j = 0, grid%ny + 1
        do i = 0, grid%nx + 1
          x = node_position(grid, c, i, j, k)
          field(i, j, k) = speed * cos(2.0_wp * pi * (x(1) + 2.0_wp * x(2) + 3.0_wp * x(3)) / box + c)
        end do
      end do
    end do
  end subroutine smooth_field
end module immersed_sweep_survey
