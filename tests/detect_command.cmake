# detect_command: `multislit detect` on rendered frames of the cable scenario, its JSON lines read
# back. Frame 0 sees the bare floor, frame 1 the 7 mm LAN cable. Checks the keys (the old ones
# kept), the measured sigma and its threshold, the noise rule (obstacle_points are the points of
# groups of 3 or more), the groups' sizes and extents, and that --raw lists every off-plane point.
# Run as: cmake -DMULTISLIT=<multislit> -DWORK_DIR=<dir> -P detect_command.cmake
cmake_minimum_required(VERSION 3.19)  # string(JSON)

function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGV}\n${out}")
  endif()
endfunction()

# expect(MESSAGE CONDITION...): fails with MESSAGE unless the if() condition holds.
function(expect message)
  if(NOT (${ARGN}))
    message(FATAL_ERROR "${message}")
  endif()
endfunction()

# detect(NAME FLAGS...): runs detect on the two frames, grouped and --raw; sets NAME and NAME_raw
# to the lists of their two JSON lines.
function(detect name)
  foreach(mode grouped raw)
    set(flags ${ARGN})
    if(mode STREQUAL raw)
      list(APPEND flags --raw)
    endif()
    run(${MULTISLIT} detect --reference ${WORK_DIR}/cable/reference.png ${flags}
        --out ${WORK_DIR}/${name}_${mode}.jsonl ${WORK_DIR}/cable/frame_000000.png
        ${WORK_DIR}/cable/frame_000001.png)
    file(STRINGS ${WORK_DIR}/${name}_${mode}.jsonl lines)
    list(LENGTH lines n)
    expect("${name}: detect wrote ${n} lines for 2 frames" n EQUAL 2)
    if(mode STREQUAL raw)
      set(${name}_raw "${lines}" PARENT_SCOPE)
    else()
      set(${name} "${lines}" PARENT_SCOPE)
    endif()
  endforeach()
endfunction()

# check(WHAT LINE RAW_LINE): every key; obstacle_points are exactly the points of the groups, each
# of 3 or more points with its centroid inside its extent; --raw lists every off-plane point.
# Sets count, off_plane, rejected and group_count in the caller.
function(check what line raw_line)
  foreach(key frame points found plane inliers residual_std obstacle_count stamp_us time_ms
          obstacle_points sigma_px sigma_estimate_px threshold_px off_plane_count rejected_groups
          groups)
    string(JSON type ERROR_VARIABLE missing TYPE "${line}" ${key})
    expect("${what}: no key ${key}: ${missing}" missing STREQUAL NOTFOUND)
  endforeach()
  string(JSON found GET "${line}" found)
  expect("${what}: no floor" found)
  string(JSON count GET "${line}" obstacle_count)
  string(JSON listed LENGTH "${line}" obstacle_points)
  string(JSON off_plane GET "${line}" off_plane_count)
  string(JSON rejected GET "${line}" rejected_groups)
  string(JSON group_count LENGTH "${line}" groups)
  expect("${what}: obstacle_count ${count}, ${listed} points listed" count EQUAL listed)
  expect("${what}: ${count} of ${off_plane} off-plane points" NOT off_plane LESS count)
  set(in_groups 0)
  if(group_count GREATER 0)
    math(EXPR last "${group_count} - 1")
    foreach(g RANGE ${last})
      string(JSON n GET "${line}" groups ${g} points)
      expect("${what}: group ${g} has ${n} points" NOT n LESS 3)
      math(EXPR in_groups "${in_groups} + ${n}")
      foreach(axis u v)
        string(JSON c GET "${line}" groups ${g} ${axis})
        string(JSON lo GET "${line}" groups ${g} ${axis}_min)
        string(JSON hi GET "${line}" groups ${g} ${axis}_max)
        expect("${what}: group ${g} ${axis} ${c} not in [${lo}, ${hi}]"
               NOT c LESS lo AND NOT c GREATER hi)
      endforeach()
    endforeach()
  endif()
  expect("${what}: groups hold ${in_groups} points, ${count} listed" in_groups EQUAL count)
  string(JSON raw_count GET "${raw_line}" obstacle_count)
  string(JSON raw_listed LENGTH "${raw_line}" obstacle_points)
  expect("${what}: --raw lists ${raw_listed} points, ${off_plane} off the plane"
         raw_count EQUAL off_plane AND raw_listed EQUAL off_plane)
  foreach(out count off_plane rejected group_count)
    set(${out} ${${out}} PARENT_SCOPE)
  endforeach()
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
run(${MULTISLIT} simulate --scenario cable --frames 2 --step 0.2 --out ${WORK_DIR}/cable)

# 1. Sigma measured per frame: the rendered floor scatters by about 0.12 px, so sigma is clamped
# to min_sigma (0.3 px) and the threshold is the paper's 0.9 px. The bare floor has no obstacle
# point; the cable is one or a few groups of many points.
detect(measured)
foreach(k 0 1)
  list(GET measured ${k} line)
  list(GET measured_raw ${k} raw_line)
  check("frame ${k}" "${line}" "${raw_line}")
  string(JSON sigma GET "${line}" sigma_px)
  string(JSON estimate GET "${line}" sigma_estimate_px)
  string(JSON threshold GET "${line}" threshold_px)
  expect("frame ${k}: sigma ${sigma}, threshold ${threshold} px, expected 0.3 and 0.9"
         sigma EQUAL 0.3 AND threshold EQUAL 0.9)
  expect("frame ${k}: sigma estimate ${estimate} px" estimate GREATER 0.04 AND estimate LESS 0.15)
  set(count_${k} ${count})
  set(groups_${k} ${group_count})
endforeach()
expect("bare floor: ${count_0} obstacle points" count_0 EQUAL 0)
expect("cable: ${groups_1} groups" groups_1 GREATER 0 AND groups_1 LESS 4)
expect("cable: ${count_1} obstacle points" count_1 GREATER 30)

# 2. A fixed sigma of 0.1 px (0.3 px threshold) on the bare floor: noise crosses it, mostly as
# single points, which the noise rule drops and --raw keeps.
detect(fixed --fixed-sigma --sigma 0.1)
list(GET fixed 0 line)
list(GET fixed_raw 0 raw_line)
check("bare floor at 0.3 px" "${line}" "${raw_line}")
string(JSON sigma GET "${line}" sigma_px)
string(JSON estimate TYPE "${line}" sigma_estimate_px)
string(JSON threshold GET "${line}" threshold_px)
expect("fixed sigma: ${sigma}, estimate ${estimate}, threshold ${threshold}"
       sigma EQUAL 0.1 AND estimate STREQUAL NULL AND threshold EQUAL 0.3)
expect("bare floor at 0.3 px: ${off_plane} off the plane, ${count} kept, ${rejected} rejected"
       off_plane GREATER count AND rejected GREATER 0)
# 3. --along-row measures the centre along the row, as the paper does: the same floor found,
# with the row's larger noise (about 0.12 px against 0.07 px across the stripe).
detect(along --along-row)
list(GET measured 0 line)
string(JSON across GET "${line}" sigma_estimate_px)
list(GET along 0 line)
list(GET along_raw 0 raw_line)
check("bare floor along the row" "${line}" "${raw_line}")
string(JSON along_estimate GET "${line}" sigma_estimate_px)
expect("--along-row: sigma estimate ${along_estimate} px, across the stripe ${across} px"
       along_estimate GREATER across AND along_estimate LESS 0.2)

message(STATUS "sigma estimate across the stripe ${across} px, along the row ${along_estimate} px")
message(STATUS "cable: ${count_1} points in ${groups_1} groups; bare floor at a 0.3 px threshold: "
               "${off_plane} off the plane, ${rejected} groups rejected, ${count} points kept")
