/* A run's status as a whole (bkf_scene_run_status), which bkfront run
 * exits with: the gravest of its steps' statuses, by the documented order,
 * whatever order the steps ended in. */
#include "harness.h"

#include "bkfront/scene.h"

TEST(scene_run_status_is_the_gravest_step_s)
{
    const int ok[] = {BKF_OK, BKF_OK};
    CHECK_STATUS(bkf_scene_run_status(ok, 2), BKF_OK);
    CHECK_STATUS(bkf_scene_run_status(NULL, 0), BKF_OK);
    const int numeric_first[] = {BKF_OK, BKF_ENUMERIC, BKF_EIO};
    CHECK_STATUS(bkf_scene_run_status(numeric_first, 3), BKF_ENUMERIC);
    const int io_first[] = {BKF_EIO, BKF_ENUMERIC};
    CHECK_STATUS(bkf_scene_run_status(io_first, 2), BKF_EIO);
    const int input[] = {BKF_ENUMERIC, BKF_EINPUT, BKF_EIO};
    CHECK_STATUS(bkf_scene_run_status(input, 3), BKF_EINPUT);
    const int canceled[] = {BKF_EINPUT, BKF_ECANCELED, BKF_ENUMERIC};
    CHECK_STATUS(bkf_scene_run_status(canceled, 3), BKF_ECANCELED);
    const int memory[] = {BKF_ECANCELED, BKF_OK, BKF_ENOMEM, BKF_EINPUT};
    CHECK_STATUS(bkf_scene_run_status(memory, 4), BKF_ENOMEM);
    /* only the first n count */
    CHECK_STATUS(bkf_scene_run_status(memory, 2), BKF_ECANCELED);
}
