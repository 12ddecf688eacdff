//! Reliability: no input aborts a run, no output destroys a file, every failure
//! says what it is. One module per problem, each opening with its cause; the malformed
//! inputs are built in the tests; the helpers are the crate's `common`.

mod batch_under_address_limit;
mod control_bytes_in_errors;
mod empty_inputs;
mod eval_convert_up;
mod eval_scores_detect;
mod fine_voxel_budget;
mod floor_not_at_zero;
mod header_count_too_small;
mod huge_coordinates;
mod large_connected_floor;
mod mesh_file_size;
mod millimetres_warn_first;
mod misleading_messages;
mod model_absurd_numbers;
mod obj_nan_area_cap;
mod off_corner_overflow;
mod output_is_input;
mod pcd_huge_record;
mod per_input_name_clash;
mod resume_keeps_run_outputs;
mod resume_other_models;
mod special_files_and_links;
mod stale_temp_files;
mod stdout_write_errors;
mod stray_point_extent;
mod write_errors_say_write;
