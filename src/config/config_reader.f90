!> Reading and checking the whole deck, before anything is allocated.
module config_reader
  use agglo_config, only: agglo_config_t, deck_group_names
  use config_checks, only: check_cross_groups
  use deck_file, only: deck_t, deck_load, deck_check_groups
  use config_run, only: read_run_group, check_run_group
  use config_grid, only: read_grid_group, check_grid_group
  use config_fluid, only: read_fluid_group, check_fluid_group
  use config_scene, only: read_scene_group, check_scene_group
  use config_output, only: read_output_group, check_output_group
  use config_forcing, only: read_forcing_group, check_forcing_group
  use config_pair, only: read_pair_group, check_pair_group
  use config_dlvo, only: read_dlvo_group, check_dlvo_group
  use config_collision, only: read_collision_group, check_collision_group
  use config_bodies, only: read_bodies_group, check_bodies_group
  implicit none
  private
  public :: read_config, parse_config

contains

  !> Load the deck file (rank 0 reads, all ranks receive it), parse and check it.
  subroutine read_config(path, nranks, cfg)
    character(len=*), intent(in) :: path
    integer, intent(in) :: nranks
    type(agglo_config_t), intent(out) :: cfg
    type(deck_t) :: deck
    call deck_load(path, deck)
    call parse_config(deck, nranks, cfg)
    cfg%deck_path = path
  end subroutine read_config

  !> Every group is read (defaults where absent) and checked; groups that the scene does not
  !> switch on are read too, so a typo in them is still caught, but only checked when used.
  subroutine parse_config(deck, nranks, cfg)
    type(deck_t), intent(in) :: deck
    integer, intent(in) :: nranks
    type(agglo_config_t), intent(out) :: cfg
    call deck_check_groups(deck, deck_group_names)
    call read_run_group(deck, cfg%run)
    call read_scene_group(deck, cfg%scene)
    call read_grid_group(deck, cfg%grid)
    call read_fluid_group(deck, cfg%fluid)
    call read_forcing_group(deck, cfg%forcing)
    call read_pair_group(deck, cfg%pair)
    call read_dlvo_group(deck, cfg%dlvo)
    call read_collision_group(deck, cfg%collision)
    call read_output_group(deck, cfg%output)
    call read_bodies_group(deck, cfg%bodies)

    call check_run_group(cfg%run)
    call check_scene_group(cfg%scene)
    call check_output_group(cfg%output)
    if (cfg%scene%fluid /= 'none') call check_fluid_group(cfg%fluid)
    if (cfg%scene%fluid == 'resolved') call check_grid_group(cfg%grid)
    if (cfg%scene%forcing /= 'none') call check_forcing_group(cfg%forcing)
    if (cfg%scene%particles == 'prescribed') call check_bodies_group(cfg%bodies)
    if (cfg%scene%particles == 'pair') then
      call check_pair_group(cfg%pair)
      if (cfg%scene%dlvo) call check_dlvo_group(cfg%dlvo)
      if (cfg%scene%collisions) call check_collision_group(cfg%collision)
    end if
    call check_cross_groups(cfg, nranks)
  end subroutine parse_config
end module config_reader
