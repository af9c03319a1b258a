!> particles.h5 of the resolved scene with bodies in prescribed motion (`&scene particles =
!> 'prescribed'`): one row per fluid step with every body's pose, prescribed velocity and angular
!> velocity and its hydrodynamic force and torque (the loads `load_method` selects), in the layout
!> of the pair scenes' time series (/time, /particle<n>/..., docs/outputs.md), so the same readers
!> work. bodies_loads.dat keeps the text form with both load methods and the solver's figures.
!>
!> Restart: the file holds one row per step from step 1, so a run continuing from the checkpoint
!> of step S keeps the first S rows and appends after them (particle_output_continue).
module bodies_particle_output
  use agglo_kinds, only: wp, i8
  use file_system, only: file_exists
  use parallel_env, only: any_rank
  use config_bodies, only: bodies_config_t
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_output_open, particle_output_continue, &
                             sample_value, sample_end
  use immersed_geometry, only: immersed_body_t
  use immersed_scene, only: immersed_scene_t, motion_body, motion_velocity
  implicit none
  private
  public :: bodies_output_open, bodies_output_row

contains

  !> Create particles.h5 at path, or on a restart continue it after the checkpoint's step (collective).
  subroutine bodies_output_open(out, path, bodies, run_name, seed, restart, last_step)
    type(particle_output_t), intent(out) :: out
    character(len=*), intent(in) :: path
    type(bodies_config_t), intent(in) :: bodies
    character(len=*), intent(in) :: run_name
    integer(i8), intent(in) :: seed
    logical, intent(in) :: restart
    integer(i8), intent(in) :: last_step        !< on a restart: the checkpoint's step (= rows kept)
    type(pair_run_metadata_t) :: metadata
    ! Rank 0 alone opens the file; every rank takes the same branch on its answer.
    if (restart .and. any_rank(file_exists(path))) then
      call particle_output_continue(out, path, bodies%count, last_step, 0_i8)
      return
    end if
    metadata%name = run_name
    metadata%shape = bodies%shape(1)
    if (any(bodies%shape(2:bodies%count) /= bodies%shape(1))) metadata%shape = 'mixed'
    metadata%aspect_ratio = bodies%aspect_ratio(1)
    metadata%radius = bodies%radius(1)
    metadata%fluid = 'prescribed'
    metadata%seed = seed
    metadata%bodies = bodies%count
    call particle_output_open(out, path, metadata)
  end subroutine bodies_output_open

  !> The row of the step just taken, at time (s), in a box of the given lengths (m).
  subroutine bodies_output_row(out, scene, time, box)
    type(particle_output_t), intent(inout) :: out
    type(immersed_scene_t), intent(in) :: scene
    real(wp), intent(in) :: time, box(3)
    type(immersed_body_t) :: body
    character(len=32) :: group
    integer :: n
    if (.not. out%active) return
    call sample_value(out, 'time', time)
    do n = 1, size(scene%motion)
      body = motion_body(scene%motion(n), time, box)
      write(group, '(a,i0,a)') 'particle', n, '/'
      call sample_value(out, trim(group)//'position', body%centre)
      call sample_value(out, trim(group)//'quaternion', body%orientation)
      call sample_value(out, trim(group)//'velocity', motion_velocity(scene%motion(n), time))
      call sample_value(out, trim(group)//'angular_velocity', scene%motion(n)%angular_velocity)
      call sample_value(out, trim(group)//'force_hydrodynamic', scene%force(:, n))
      call sample_value(out, trim(group)//'torque_hydrodynamic', scene%torque(:, n))
    end do
    call sample_end(out)
  end subroutine bodies_output_row
end module bodies_particle_output
