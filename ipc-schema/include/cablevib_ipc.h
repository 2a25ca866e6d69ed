/*
 * cablevib_ipc.h - C/C++ mirror of the cablevib-ipc message types (schema v4).
 *
 * The Rust crate cablevib-ipc (ipc-schema/) is the reference; its test tests/c_header.rs
 * compiles this header and checks every size, alignment, offset, field type and constant
 * against the Rust layout. Do not edit one without the other.
 *
 * Units: SI, in the field names: m (_m), N (_n), Hz (_hz), ns (_ns). Quaternions are
 * [w, x, y, z], identity [1, 0, 0, 0]. Every *timestamp_ns is CLOCK_MONOTONIC in ns:
 *     struct timespec ts; clock_gettime(CLOCK_MONOTONIC, &ts);
 *     uint64_t now_ns = (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
 * reserved* fields are explicit padding: write 0.
 *
 * With iceoryx2-cxx, each struct carries IOX2_TYPE_NAME (the Rust #[type_name]); a peer built
 * against another schema version is refused when it opens the service.
 */
#ifndef CABLEVIB_IPC_H
#define CABLEVIB_IPC_H

#include <stddef.h>
#include <stdint.h>

/* ---- constants --------------------------------------------------------------------------- */

#define CABLEVIB_SCHEMA_VERSION 4u
#define CABLEVIB_MAX_CABLES 16
#define CABLEVIB_MAX_STIFFNESS_DIM 6

/* Service names (prefix them with "<instance>/" to run several instances). */
#define CABLEVIB_SERVICE_POSE "cablevib/pose"         /* publish-subscribe, PoseSample     */
#define CABLEVIB_SERVICE_T_MIN "cablevib/t_min"       /* publish-subscribe, TminSetpoint   */
#define CABLEVIB_SERVICE_ESTIMATE "cablevib/estimate" /* publish-subscribe, EstimateSample */
#define CABLEVIB_SERVICE_MARGIN "cablevib/margin"     /* request-response, MarginRequest -> MarginResponse */
#define CABLEVIB_SERVICE_VIBRATION "cablevib/vibration" /* publish-subscribe, VibrationSample (optional) */

/* Event services (wake-ups for peers that block instead of busy-polling): notify
 * CABLEVIB_SERVICE_WAKE_SERVICE after sending a pose, set-point or margin request; cablevib
 * notifies CABLEVIB_SERVICE_WAKE_CONTROLLER after each estimate and margin response. */
#define CABLEVIB_SERVICE_WAKE_SERVICE "cablevib/wake/service"
#define CABLEVIB_SERVICE_WAKE_CONTROLLER "cablevib/wake/controller"
#define CABLEVIB_EVENT_ID_POSE 1
#define CABLEVIB_EVENT_ID_T_MIN 2
#define CABLEVIB_EVENT_ID_MARGIN_REQUEST 3
#define CABLEVIB_EVENT_ID_ESTIMATE 4
#define CABLEVIB_EVENT_ID_MARGIN_RESPONSE 5
#define CABLEVIB_EVENT_ID_VIBRATION 6

/* ee_mode_age_cycles / t_min_required_age_cycles when nothing is known. */
#define CABLEVIB_AGE_UNKNOWN 4294967295u

/* measured_age_ns when no frequency is measured. */
#define CABLEVIB_MEASURED_AGE_UNKNOWN 18446744073709551615u

/* cablevib_vibration_sample_t.flags: angular_velocity_rad_s holds a measurement. */
#define CABLEVIB_VIBRATION_FLAG_ANGULAR_VELOCITY 1u

/* The range of a margin request's required_f1_hz, Hz; outside it: status invalid_request. */
#define CABLEVIB_REQUIRED_F1_MIN_HZ 1e-6
#define CABLEVIB_REQUIRED_F1_MAX_HZ 1e6

/* iceoryx2 type names; they end with "::v<CABLEVIB_SCHEMA_VERSION>". */
#define CABLEVIB_TYPE_NAME_POSE_SAMPLE "cablevib::PoseSample::v4"
#define CABLEVIB_TYPE_NAME_T_MIN_SETPOINT "cablevib::TminSetpoint::v4"
#define CABLEVIB_TYPE_NAME_ESTIMATE_SAMPLE "cablevib::EstimateSample::v4"
#define CABLEVIB_TYPE_NAME_MARGIN_REQUEST "cablevib::MarginRequest::v4"
#define CABLEVIB_TYPE_NAME_MARGIN_RESPONSE "cablevib::MarginResponse::v4"
#define CABLEVIB_TYPE_NAME_VIBRATION_SAMPLE "cablevib::VibrationSample::v4"

/* Status codes (the uint32_t `status` fields). Values never change; treat unknown ones as
 * "not valid". */
typedef enum cablevib_status {
    CABLEVIB_STATUS_OK = 0,
    CABLEVIB_STATUS_TENSION_INFEASIBLE = 1,
    CABLEVIB_STATUS_INVALID_INPUT = 2,      /* non-finite or malformed input, e.g. an orientation
                                             * other than the identity (vector part over 1e-3
                                             * of the norm) on a point-mass end-effector */
    CABLEVIB_STATUS_NOT_CONVERGED = 3,
    CABLEVIB_STATUS_RANK_DEFICIENT = 4,
    CABLEVIB_STATUS_OUTSIDE_WORKSPACE = 5,
    CABLEVIB_STATUS_NO_POSE_YET = 6,
    CABLEVIB_STATUS_NON_UNIT_QUATERNION = 7,
    CABLEVIB_STATUS_T_MIN_OUT_OF_RANGE = 8,
    CABLEVIB_STATUS_INVALID_REQUEST = 9,
    CABLEVIB_STATUS_INTERNAL_ERROR = 10,
    CABLEVIB_STATUS_CABLE_SLACK = 11,
    CABLEVIB_STATUS_MECHANISM = 12
} cablevib_status_t;

/* Measured-frequency status codes (the uint32_t measured_*_status fields of the estimate):
 * only OK carries a number. Values never change; treat unknown ones as "no measurement". */
typedef enum cablevib_measured_status {
    CABLEVIB_MEASURED_OK = 0,
    CABLEVIB_MEASURED_NO_INPUT = 1,       /* no vibration sample within the silence time */
    CABLEVIB_MEASURED_FILLING = 2,        /* the window is not full yet */
    CABLEVIB_MEASURED_NO_PEAK = 3,        /* no peak stands above the band's floor */
    CABLEVIB_MEASURED_NO_MODEL = 4,       /* the model's frequency is not known */
    CABLEVIB_MEASURED_BAND_TOO_HIGH = 5,  /* the band reaches above 0.4 x the sample rate */
    CABLEVIB_MEASURED_BAND_TOO_LOW = 6,   /* the band reaches below 4 / window */
    CABLEVIB_MEASURED_INPUT_FAULT = 7,    /* too many missing samples in the window */
    CABLEVIB_MEASURED_RATE_TOO_HIGH = 8,  /* the sample rate is above the service's maximum */
    CABLEVIB_MEASURED_OUTSIDE_BAND = 9    /* the strongest vibration near the band lies outside it */
} cablevib_measured_status_t;

#ifdef __cplusplus
#define CABLEVIB_IOX2_TYPE_NAME(name) static constexpr const char* IOX2_TYPE_NAME = name;
#define CABLEVIB_STATIC_ASSERT(cond, msg) static_assert(cond, msg)
#else
#define CABLEVIB_IOX2_TYPE_NAME(name)
#define CABLEVIB_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#endif

/* ---- messages ---------------------------------------------------------------------------- */

/* End-effector pose, controller -> cablevib on CABLEVIB_SERVICE_POSE. 80 bytes. */
typedef struct cablevib_pose_sample {
    CABLEVIB_IOX2_TYPE_NAME(CABLEVIB_TYPE_NAME_POSE_SAMPLE)
    uint64_t sequence;           /* sender's sequence number, +1 per pose; echoed by the estimate */
    uint64_t timestamp_ns;       /* sender's CLOCK_MONOTONIC, ns */
    double position_m[3];        /* position in the base frame, m */
    double orientation_wxyz[4];  /* unit quaternion [w, x, y, z] */
    uint32_t flags;              /* reserved for flags: write 0 */
    uint32_t reserved0;          /* padding: write 0 */
} cablevib_pose_sample_t;

/* Minimum-tension set-point, controller -> cablevib on CABLEVIB_SERVICE_T_MIN. 160 bytes.
 * per_cable_count == 0: every cable uses t_min_n; otherwise cable i < per_cable_count uses
 * per_cable_t_min_n[i] and the others t_min_n. Applies from the next cycle. */
typedef struct cablevib_t_min_setpoint {
    CABLEVIB_IOX2_TYPE_NAME(CABLEVIB_TYPE_NAME_T_MIN_SETPOINT)
    uint64_t sequence;
    uint64_t timestamp_ns;                          /* sender's CLOCK_MONOTONIC, ns */
    double t_min_n;                                 /* N */
    uint32_t per_cable_count;                       /* 0 = t_min_n for all */
    uint32_t reserved0;                             /* padding: write 0 */
    double per_cable_t_min_n[CABLEVIB_MAX_CABLES];  /* N */
} cablevib_t_min_setpoint_t;

/* Estimate, cablevib -> controller on CABLEVIB_SERVICE_ESTIMATE. 592 bytes.
 * Echoes the answered pose's sequence and timestamp: compare pose_sequence with the last pose
 * sent to tell fresh from stale. Values are meaningful only when status == CABLEVIB_STATUS_OK
 * (frequencies are NaN otherwise). */
typedef struct cablevib_estimate_sample {
    CABLEVIB_IOX2_TYPE_NAME(CABLEVIB_TYPE_NAME_ESTIMATE_SAMPLE)
    uint64_t pose_sequence;         /* sequence of the pose answered */
    uint64_t pose_timestamp_ns;     /* timestamp_ns of that pose */
    uint64_t receive_timestamp_ns;  /* cablevib's CLOCK_MONOTONIC when it took the pose */
    uint64_t publish_timestamp_ns;  /* cablevib's CLOCK_MONOTONIC before publishing */
    uint32_t status;                /* cablevib_status_t */
    uint32_t cable_count;           /* valid entries of tensions_n */
    double tensions_n[CABLEVIB_MAX_CABLES];  /* N */
    double f1_hz;                   /* first natural frequency, Hz */
    double ee_mode_hz;              /* lowest mode with end-effector participation >= the
                                     * scene's threshold, Hz, as of ee_mode_age_cycles
                                     * estimates ago; NaN when none is known */
    uint32_t stiffness_dim;         /* 3 (x, y, z) or 6 (x, y, z, rx, ry, rz) */
    uint32_t ee_mode_age_cycles;    /* 0: computed and certified at this pose; k: the answer
                                     * of k estimates ago (the work that did not fit in the
                                     * per-cycle evaluation budget goes on over the next
                                     * cycles); CABLEVIB_AGE_UNKNOWN: none known (NaN) */
    /* row-major, packed: entry (r, c) is stiffness[r * stiffness_dim + c];
     * N/m, N*m/rad, N/rad */
    double stiffness[CABLEVIB_MAX_STIFFNESS_DIM * CABLEVIB_MAX_STIFFNESS_DIM];
    uint64_t compute_ns;            /* compute time of this estimate, ns */
    uint32_t eigen_evaluations;     /* evaluations of D(lambda) this cycle (<= the budget) */
    uint32_t tension_iterations;
    double eigen_residual;          /* |mu_1(D(l))| / (l * max|D'(l)|) at the solver's last
                                     * iterate l: the smallest eigenvalue of the condensed
                                     * dynamic stiffness against the inertia term it cancels,
                                     * to first order the relative distance of l to the root;
                                     * <= 1e-9 on converged answers (dimensionless) */
    uint64_t skipped_poses;         /* poses skipped since start (a newer one was queued) */
    uint64_t sequence;              /* the service's estimate count: 1 for its first estimate,
                                     * +1 per estimate; a gap is estimates lost on the way */
    double measured_f1_hz;          /* dominant measured frequency near f1_hz, Hz; NaN unless
                                     * measured_f1_status == CABLEVIB_MEASURED_OK */
    double f1_residual_hz;          /* f1_hz - measured_f1_hz (model - measured), Hz; NaN when
                                     * either is absent */
    double measured_ee_mode_hz;     /* dominant measured frequency near ee_mode_hz, Hz */
    double ee_mode_residual_hz;     /* ee_mode_hz - measured_ee_mode_hz, Hz */
    uint64_t measured_age_ns;       /* receive_timestamp_ns - centre of the measured window, ns;
                                     * CABLEVIB_MEASURED_AGE_UNKNOWN when nothing is measured */
    uint32_t measured_f1_status;    /* cablevib_measured_status_t */
    uint32_t measured_ee_mode_status; /* cablevib_measured_status_t */
    uint64_t vibration_samples;     /* vibration samples taken since start */
    uint64_t vibration_refused;     /* refused since start (not finite, beyond 1e6 m/s^2,
                                     * sequence or time not after the previous) */
    uint64_t vibration_lost;        /* never received since start (sequence gaps) */
} cablevib_estimate_sample_t;

/* Margin query, controller -> cablevib on CABLEVIB_SERVICE_MARGIN (request). 24 bytes. */
typedef struct cablevib_margin_request {
    CABLEVIB_IOX2_TYPE_NAME(CABLEVIB_TYPE_NAME_MARGIN_REQUEST)
    uint64_t sequence;       /* echoed as request_sequence */
    uint64_t timestamp_ns;   /* requester's CLOCK_MONOTONIC, ns */
    double required_f1_hz;   /* required first natural frequency, Hz, in [CABLEVIB_REQUIRED_F1_MIN_HZ, _MAX_HZ] */
} cablevib_margin_request_t;

/* Margin answer for the latest estimated pose (response). 64 bytes. NaN unless status OK. */
typedef struct cablevib_margin_response {
    CABLEVIB_IOX2_TYPE_NAME(CABLEVIB_TYPE_NAME_MARGIN_RESPONSE)
    uint64_t request_sequence;  /* sequence of the request answered */
    uint64_t pose_sequence;     /* pose the answer is based on (0 if none) */
    uint32_t status;            /* cablevib_status_t */
    uint32_t t_min_required_age_cycles; /* 0: t_min_required_n at pose_sequence's pose; k: at
                                         * the pose k estimates earlier (the inverse search
                                         * runs beside the estimate loop);
                                         * CABLEVIB_AGE_UNKNOWN: not known (NaN) */
    double f1_hz;               /* Hz */
    double margin_hz;           /* f1_hz - required_f1_hz, Hz */
    double margin_ratio;        /* f1_hz / required_f1_hz */
    double t_min_required_n;    /* smallest T_min (every cable) reaching this requirement, N;
                                 * +INFINITY if no feasible T_min reaches it; NaN while not
                                 * known. A failed search answers with its own status (not
                                 * OK) and its age */
    uint64_t timestamp_ns;      /* cablevib's CLOCK_MONOTONIC when answering, ns */
} cablevib_margin_response_t;

/* A sample of a sensor on the platform (accelerometer or IMU), sensor -> cablevib on
 * CABLEVIB_SERVICE_VIBRATION (optional). 72 bytes. Send every sample in order: sequence is
 * its place in the sensor's uniform sample grid, timestamp_ns when it was taken. */
typedef struct cablevib_vibration_sample {
    CABLEVIB_IOX2_TYPE_NAME(CABLEVIB_TYPE_NAME_VIBRATION_SAMPLE)
    uint64_t sequence;                 /* +1 per sample; a gap is a lost sample */
    uint64_t timestamp_ns;             /* CLOCK_MONOTONIC when the sample was taken, ns */
    double acceleration_m_s2[3];       /* specific force along the sensor's axes, m/s^2 */
    double angular_velocity_rad_s[3];  /* rad/s, when flags has the angular-velocity bit */
    uint32_t flags;                    /* CABLEVIB_VIBRATION_FLAG_ANGULAR_VELOCITY or 0 */
    uint32_t reserved0;                /* padding: write 0 */
} cablevib_vibration_sample_t;

/* ---- layout checks (the Rust side asserts the same numbers) ------------------------------- */

CABLEVIB_STATIC_ASSERT(sizeof(double) == 8, "cablevib_ipc.h needs 64-bit IEEE doubles");
CABLEVIB_STATIC_ASSERT(sizeof(cablevib_pose_sample_t) == 80, "cablevib_pose_sample_t size");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_pose_sample_t, flags) == 72, "cablevib_pose_sample_t layout");
CABLEVIB_STATIC_ASSERT(sizeof(cablevib_t_min_setpoint_t) == 160, "cablevib_t_min_setpoint_t size");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_t_min_setpoint_t, per_cable_t_min_n) == 32, "cablevib_t_min_setpoint_t layout");
CABLEVIB_STATIC_ASSERT(sizeof(cablevib_estimate_sample_t) == 592, "cablevib_estimate_sample_t size");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_estimate_sample_t, stiffness) == 192, "cablevib_estimate_sample_t layout");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_estimate_sample_t, skipped_poses) == 504, "cablevib_estimate_sample_t layout");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_estimate_sample_t, sequence) == 512, "cablevib_estimate_sample_t layout");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_estimate_sample_t, measured_f1_hz) == 520, "cablevib_estimate_sample_t layout");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_estimate_sample_t, vibration_lost) == 584, "cablevib_estimate_sample_t layout");
CABLEVIB_STATIC_ASSERT(sizeof(cablevib_margin_request_t) == 24, "cablevib_margin_request_t size");
CABLEVIB_STATIC_ASSERT(sizeof(cablevib_margin_response_t) == 64, "cablevib_margin_response_t size");
CABLEVIB_STATIC_ASSERT(offsetof(cablevib_margin_response_t, timestamp_ns) == 56, "cablevib_margin_response_t layout");
CABLEVIB_STATIC_ASSERT(sizeof(cablevib_vibration_sample_t) == 72, "cablevib_vibration_sample_t size");

#endif /* CABLEVIB_IPC_H */
