! checks: 4
!> Unit tests of particle_system_checkpoint (the checkpoint group 'particles'): 40 spheres in a
!> periodic box with a finite interaction gap (pair records for the near pairs only) written to a
!> checkpoint and read back into a system created from the initial bodies: the records are the saved
!> ones (particles/pairs) and the run continues bit for bit; a two-body system writes no
!> particles/pairs (the pair scenes' layout) and reads back the same.
program test_particle_system_checkpoint
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use run_directory, only: prepare_run_directory
  use checkpoint_files, only: checkpoint_t, checkpoint_begin, checkpoint_commit, checkpoint_open, checkpoint_path
  use hdf5_files, only: h5_close, h5_exists
  use parallel_env, only: parallel_start, barrier, my_rank
  use config_collision, only: collision_config_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use collision, only: collision_setup
  use particle_system, only: particle_models_t, particle_system_t, particle_system_create, particle_system_interact, &
                             particle_system_step
  use particle_system_checkpoint, only: write_particle_system_checkpoint, read_particle_system_checkpoint
  use test_framework, only: test_start, test_finish, check
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp, dt = 1.0e-7_wp
  type(agglo_config_t) :: cfg
  integer :: status

  call parallel_start()
  call test_start('particle_system_checkpoint')
  cfg%output%directory = 'test_particle_system_checkpoint_run'
  cfg%run%overwrite = .true.
  if (my_rank == 0) call execute_command_line('rm -rf test_particle_system_checkpoint_run', exitstat=status)
  call barrier()
  call prepare_run_directory(cfg)
  call round_trip(40, 10_i8, 'many_bodies')
  call round_trip(2, 20_i8, 'two_bodies')
  call test_finish()

contains

  !> n spheres at random (no two closer than 1 um) in a periodic cube at 20% by volume, random
  !> velocities, collisions; 500 steps, checkpoint, 500 more; read back into a fresh system, 500 steps.
  subroutine round_trip(n, step, name)
    integer, intent(in) :: n
    integer(i8), intent(in) :: step
    character(len=*), intent(in) :: name
    type(spheroid_t) :: sphere
    type(rigid_body_t) :: bodies(n)
    type(particle_system_t) :: straight, restarted
    type(particle_models_t) :: models
    type(checkpoint_t) :: checkpoint
    type(random_stream_t) :: stream
    real(wp) :: box, position(3)
    integer :: i, j, k
    logical :: clear, same, has_pairs
    sphere = make_spheroid('sphere', radius, density)
    box = (real(n, wp) * (4.0_wp / 3.0_wp) * acos(-1.0_wp) * radius**3 / 0.2_wp)**(1.0_wp / 3.0_wp)
    call stream_seed(stream, 7_i8, n)
    do i = 1, n
      do
        position = box * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
        clear = .true.
        do j = 1, i - 1
          clear = clear .and. norm2(position - bodies(j)%position - box * anint((position - bodies(j)%position) / box)) &
                              > 2.0_wp * radius + 1.0e-6_wp
        end do
        if (clear) exit
      end do
      call rigid_body_of_spheroid(bodies(i), sphere, position, [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
          velocity=0.2_wp * [stream_normal(stream), stream_normal(stream), stream_normal(stream)])
    end do
    models%collisions = .true.
    call collision_setup(models%collision_model, collision_config_t())
    models%integrator = integrator_euler
    if (n > 2) models%interaction_gap = 0.2_wp * radius
    call particle_system_create(straight, spread(sphere, 1, n), bodies, models, box_length=[box, box, box])
    call particle_system_interact(straight, dt)
    do k = 1, 500
      call particle_system_step(straight, dt)
    end do
    call checkpoint_begin(checkpoint, step)
    call write_particle_system_checkpoint(checkpoint, straight)
    call checkpoint_commit(checkpoint, 5)
    do k = 1, 500
      call particle_system_step(straight, dt)
    end do
    call particle_system_create(restarted, spread(sphere, 1, n), bodies, models, box_length=[box, box, box])
    call checkpoint_open(checkpoint, checkpoint_path(step))
    has_pairs = h5_exists(checkpoint%file, 'particles/pairs')
    call read_particle_system_checkpoint(checkpoint, restarted)
    call h5_close(checkpoint%file)
    do k = 1, 500
      call particle_system_step(restarted, dt)
    end do
    ! Exact comparison on purpose: a restart must reproduce the uninterrupted run bit for bit.
    same = size(restarted%pairs) == size(straight%pairs) .and. restarted%collisions_total == straight%collisions_total
    if (same) same = all(restarted%pairs%first == straight%pairs%first) .and. &
                     all(restarted%pairs%second == straight%pairs%second)
    do i = 1, n
      same = same .and. all(restarted%bodies(i)%position == straight%bodies(i)%position) .and. &
             all(restarted%bodies(i)%velocity == straight%bodies(i)%velocity)
    end do
    call check(same, name//'_restart_bit_for_bit')
    if (n > 2) then
      call check(has_pairs .and. size(straight%pairs) < n * (n - 1) / 2, name//'_pair_records_named')
    else
      call check(.not. has_pairs, name//'_pair_scene_layout')
    end if
  end subroutine round_trip

end program test_particle_system_checkpoint
