!> The whole deck as one derived type: one component per namelist group.
module agglo_config
  use config_run, only: run_config_t, write_run_group
  use config_grid, only: grid_config_t, write_grid_group
  use config_fluid, only: fluid_config_t, write_fluid_group
  use config_scene, only: scene_config_t, write_scene_group
  use config_output, only: output_config_t, write_output_group
  use config_forcing, only: forcing_config_t, write_forcing_group
  use config_pair, only: pair_config_t, write_pair_group
  use config_dlvo, only: dlvo_config_t, write_dlvo_group
  use config_collision, only: collision_config_t, write_collision_group
  use namelist_text, only: namelist_item_t, read_namelist_items
  use error_handling, only: fatal
  use config_bodies, only: bodies_config_t, write_bodies_group
  use config_suspension, only: suspension_config_t, write_suspension_group
  use file_system, only: longest_path
  implicit none
  private
  public :: agglo_config_t, deck_group_names, write_config, config_items

  type :: agglo_config_t
    type(run_config_t) :: run
    type(grid_config_t) :: grid
    type(fluid_config_t) :: fluid
    type(scene_config_t) :: scene
    type(output_config_t) :: output
    type(forcing_config_t) :: forcing
    type(pair_config_t) :: pair
    type(dlvo_config_t) :: dlvo
    type(collision_config_t) :: collision
    type(bodies_config_t) :: bodies
    type(suspension_config_t) :: suspension
    character(len=longest_path) :: deck_path = ''   !< the deck file this configuration came from
  end type agglo_config_t

  !> Every namelist group a deck may contain.
  character(len=16), parameter :: deck_group_names(11) = [character(len=16) :: &
      'run', 'scene', 'grid', 'fluid', 'forcing', 'pair', 'dlvo', 'collision', 'output', 'bodies', 'suspension']

contains

  !> The fully resolved deck (defaults included) as namelists: a valid deck that reproduces the run.
  subroutine write_config(unit, cfg)
    integer, intent(in) :: unit
    type(agglo_config_t), intent(in) :: cfg
    call write_run_group(unit, cfg%run)
    call write_scene_group(unit, cfg%scene)
    call write_grid_group(unit, cfg%grid)
    call write_fluid_group(unit, cfg%fluid)
    call write_forcing_group(unit, cfg%forcing)
    call write_pair_group(unit, cfg%pair)
    call write_dlvo_group(unit, cfg%dlvo)
    call write_collision_group(unit, cfg%collision)
    call write_output_group(unit, cfg%output)
    call write_bodies_group(unit, cfg%bodies)
    call write_suspension_group(unit, cfg%suspension)
  end subroutine write_config

  !> Every variable of the configuration as (group, name, value text), through its own namelist
  !> output (a scratch file: a namelist WRITE needs a unit).
  function config_items(cfg) result(items)
    type(agglo_config_t), intent(in) :: cfg
    type(namelist_item_t), allocatable :: items(:)
    integer :: unit, ios
    open(newunit=unit, status='scratch', action='readwrite', form='formatted', delim='apostrophe', iostat=ios)
    if (ios /= 0) call fatal('deck: cannot open a scratch file to check the configuration (TMPDIR not writable?)', &
                             collective=.false.)
    call write_config(unit, cfg)
    call read_namelist_items(unit, items)
    close(unit)
  end function config_items
end module agglo_config
