//! The coefficients of the banded Rosenbrock methods, in the form of Hairer &
//! Wanner (Solving ODEs II, section IV.7, (7.25)) that needs no product with
//! the Jacobian: stage i solves
//!
//!   (1/(h gamma) I - W) k_i = f(t + alpha_i h, y + sum_j a_ij k_j) + sum_j (c_ij / h) k_j + d_i h f_t,
//!
//! then y_new = y + sum m_i k_i, and sum e_i k_i estimates the local error.

/// Most stages of a method here.
pub const MAX_STAGES: usize = 6;

#[derive(Debug, PartialEq)]
pub struct Tableau {
    pub name: &'static str,
    pub stages: usize,
    pub gamma: f64,
    /// Strictly lower triangular, row i for stage i.
    pub a: [[f64; MAX_STAGES]; MAX_STAGES],
    pub c: [[f64; MAX_STAGES]; MAX_STAGES],
    pub alpha: [f64; MAX_STAGES],
    pub d: [f64; MAX_STAGES],
    pub m: [f64; MAX_STAGES],
    pub e: [f64; MAX_STAGES],
    /// The local error estimate is O(h^estimate_order): the step-size controller's exponent.
    pub estimate_order: f64,
    /// Keeps its order with any matrix W in place of df/dy (a W-method): the
    /// Jacobian may be kept over steps.
    pub w_method: bool,
}

const Z: [f64; MAX_STAGES] = [0.0; MAX_STAGES];

/// RODAS4 (Hairer & Wanner; their code `rodas.f`, METH = 1): order 4, an
/// order-3 embedded solution, L-stable and stiffly accurate; needs the exact
/// Jacobian every step for its order.
pub const RODAS4: Tableau = {
    const A5: [f64; 4] = [1.221_224_509_226_641, 6.019_134_481_288_629, 12.537_083_329_320_87, -0.687_886_036_105_895];
    Tableau {
        name: "RODAS4",
        stages: 6,
        gamma: 0.25,
        a: [
            Z,
            [1.544, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.946_678_528_081_582_6, 0.255_701_169_898_328_4, 0.0, 0.0, 0.0, 0.0],
            [3.314_825_187_068_521, 2.896_124_015_972_201, 0.998_641_913_997_781_7, 0.0, 0.0, 0.0],
            [A5[0], A5[1], A5[2], A5[3], 0.0, 0.0],
            // Stiffly accurate: stage 6 is evaluated at stage 5's solution.
            [A5[0], A5[1], A5[2], A5[3], 1.0, 0.0],
        ],
        c: [
            Z,
            [-5.6688, 0.0, 0.0, 0.0, 0.0, 0.0],
            [-2.430_093_356_833_875, -0.206_359_915_709_191_5, 0.0, 0.0, 0.0, 0.0],
            [-0.107_352_905_815_137_5, -9.594_562_251_023_355, -20.470_286_148_096_16, 0.0, 0.0, 0.0],
            [7.496_443_313_967_647, -10.246_804_314_643_52, -33.999_903_528_199_05, 11.708_908_932_061_6, 0.0, 0.0],
            [8.083_246_795_921_522, -7.981_132_988_064_893, -31.521_594_328_743_71, 16.319_305_431_231_36, -6.058_818_238_834_054, 0.0],
        ],
        alpha: [0.0, 0.386, 0.21, 0.63, 1.0, 1.0],
        d: [0.25, -0.1043, 0.1035, -0.362_000_000_000_002_3e-1, 0.0, 0.0],
        // y_new = stage 6's argument + k6; k6 is its difference from the order-3 solution.
        m: [A5[0], A5[1], A5[2], A5[3], 1.0, 1.0],
        e: [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        estimate_order: 4.0,
        w_method: false,
    }
};

/// ROS34PW2 (Rang & Angermann, BIT 45 (2005) 761-787, their table of
/// ROS34PW2, turned into the form above): a W-method of order 3 with an
/// order-2 embedded solution, L-stable and stiffly accurate, four stages.
pub const ROS34PW2: Tableau = Tableau {
    name: "ROS34PW2",
    stages: 4,
    gamma: 0.435_866_521_508_459,
    a: [
        Z,
        [2.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.419_217_317_455_764_7, -0.259_232_211_672_969_6, 0.0, 0.0, 0.0, 0.0],
        [4.184_760_482_319_16, -0.285_192_017_355_495_93, 2.294_280_360_279_042, 0.0, 0.0, 0.0],
        Z,
        Z,
    ],
    c: [
        Z,
        [-4.588_560_720_558_084, 0.0, 0.0, 0.0, 0.0, 0.0],
        [-4.184_760_482_319_16, 0.285_192_017_355_495_93, 0.0, 0.0, 0.0, 0.0],
        [-6.368_179_200_128_361_5, -6.795_620_944_466_838, 2.870_098_604_331_056, 0.0, 0.0, 0.0],
        Z,
        Z,
    ],
    alpha: [0.0, 0.871_733_043_016_918, 0.731_579_957_788_852_4, 1.0, 0.0, 0.0],
    // The row sums of the paper's gamma_ij; the last is 0 (stiffly accurate).
    d: [0.435_866_521_508_459, -0.435_866_521_508_459, -0.413_333_376_233_886_5, 0.0, 0.0, 0.0],
    m: [4.184_760_482_319_16, -0.285_192_017_355_495_93, 2.294_280_360_279_041_4, 1.0, 0.0, 0.0],
    e: [0.277_749_947_647_967_45, -1.403_239_895_175_999_5, 1.772_630_127_667_550_7, 0.5, 0.0, 0.0],
    estimate_order: 3.0,
    w_method: true,
};
