//! The coefficients of the banded Rosenbrock methods, in the form of Hairer &
//! Wanner (Solving ODEs II, section IV.7, (7.25)) that needs no product with
//! the Jacobian: stage i solves
//!
//!   (1/(h gamma) I - W) k_i = f(t + alpha_i h, y + sum_j a_ij k_j) + sum_j (c_ij / h) k_j + d_i h f_t,
//!
//! then y_new = y + sum m_i k_i, and sum e_i k_i estimates the local error.

/// Most stages of a method here.
pub const MAX_STAGES: usize = 8;

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

/// A row of fewer coefficients, padded with zeros.
const fn row<const N: usize>(x: [f64; N]) -> [f64; MAX_STAGES] {
    let mut r = Z;
    let mut i = 0;
    while i < N {
        r[i] = x[i];
        i += 1;
    }
    r
}

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
            row([1.544]),
            row([0.946_678_528_081_582_6, 0.255_701_169_898_328_4]),
            row([3.314_825_187_068_521, 2.896_124_015_972_201, 0.998_641_913_997_781_7]),
            row([A5[0], A5[1], A5[2], A5[3], 0.0, 0.0]),
            // Stiffly accurate: stage 6 is evaluated at stage 5's solution.
            row([A5[0], A5[1], A5[2], A5[3], 1.0, 0.0]),
            Z,
            Z,
        ],
        c: [
            Z,
            row([-5.6688]),
            row([-2.430_093_356_833_875, -0.206_359_915_709_191_5]),
            row([-0.107_352_905_815_137_5, -9.594_562_251_023_355, -20.470_286_148_096_16]),
            row([7.496_443_313_967_647, -10.246_804_314_643_52, -33.999_903_528_199_05, 11.708_908_932_061_6]),
            row([8.083_246_795_921_522, -7.981_132_988_064_893, -31.521_594_328_743_71, 16.319_305_431_231_36, -6.058_818_238_834_054]),
            Z,
            Z,
        ],
        alpha: row([0.0, 0.386, 0.21, 0.63, 1.0, 1.0]),
        d: row([0.25, -0.1043, 0.1035, -0.362_000_000_000_002_3e-1]),
        // y_new = stage 6's argument + k6; k6 is its difference from the order-3 solution.
        m: row([A5[0], A5[1], A5[2], A5[3], 1.0, 1.0]),
        e: row([0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
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
        row([2.0]),
        row([1.419_217_317_455_764_7, -0.259_232_211_672_969_6]),
        row([4.184_760_482_319_16, -0.285_192_017_355_495_93, 2.294_280_360_279_042]),
        Z,
        Z,
        Z,
        Z,
    ],
    c: [
        Z,
        row([-4.588_560_720_558_084]),
        row([-4.184_760_482_319_16, 0.285_192_017_355_495_93]),
        row([-6.368_179_200_128_361_5, -6.795_620_944_466_838, 2.870_098_604_331_056]),
        Z,
        Z,
        Z,
        Z,
    ],
    alpha: row([0.0, 0.871_733_043_016_918, 0.731_579_957_788_852_4, 1.0]),
    // The row sums of the paper's gamma_ij; the last is 0 (stiffly accurate).
    d: row([0.435_866_521_508_459, -0.435_866_521_508_459, -0.413_333_376_233_886_5]),
    m: row([4.184_760_482_319_16, -0.285_192_017_355_495_93, 2.294_280_360_279_041_4, 1.0]),
    e: row([0.277_749_947_647_967_45, -1.403_239_895_175_999_5, 1.772_630_127_667_550_7, 0.5]),
    estimate_order: 3.0,
    w_method: true,
};

/// Rodas5P (Steinebach, "Construction of Rosenbrock-Wanner method Rodas5P and numerical
/// benchmarks within the Julia Differential Equations package", BIT 63 (2023) 27; the
/// coefficients as OrdinaryDiffEq.jl tabulates them, in the form above): order 5, an order-4
/// embedded solution, L-stable and stiffly accurate, eight stages. Like RODAS4 it needs the
/// exact Jacobian; at tight tolerances its fifth order takes longer steps.
pub const RODAS5P: Tableau = {
    const A6: [f64; 5] = [-7.502_846_399_306_121, 2.561_846_144_803_919, -11.627_539_656_261_098, -0.182_687_676_599_422_56, 0.030_198_172_008_377_946];
    Tableau {
        name: "Rodas5P",
        stages: 8,
        gamma: 0.211_937_563_194_290_14,
        a: [
            Z,
            row([3.0]),
            row([2.849_394_379_747_939, 0.458_422_422_044_639_23]),
            row([-6.954_028_509_809_101, 2.489_845_061_869_568, -10.358_996_098_473_584]),
            row([2.802_998_627_562_896_4, 0.507_246_473_622_820_6, -0.398_831_254_177_052_4, -0.047_211_872_304_046_41]),
            row(A6),
            // Stiffly accurate: stages 7 and 8 are evaluated at the solutions of 6 and 7.
            row([A6[0], A6[1], A6[2], A6[3], A6[4], 1.0]),
            row([A6[0], A6[1], A6[2], A6[3], A6[4], 1.0, 1.0]),
        ],
        c: [
            Z,
            row([-14.155_112_264_123_755]),
            row([-17.972_960_358_859_52, -2.859_693_295_451_294]),
            row([147.121_502_757_117_16, -1.412_214_027_182_13, 71.689_402_513_023_58]),
            row([165.435_170_248_716_76, -0.459_282_345_649_112_6, 42.909_383_369_586_03, -5.961_986_721_573_306]),
            row([24.854_864_614_690_072, -3.000_922_700_283_218_6, 47.493_111_002_076_8, 5.581_419_782_155_812_5, -0.661_069_182_524_947_1]),
            row([30.912_732_140_285_99, -3.120_824_334_993_797_4, 77.799_546_460_708_92, 34.286_460_282_947_83, -19.097_331_116_725_623, -28.087_943_162_872_662]),
            row([37.802_771_233_905_63, -3.257_196_902_907_227_6, 112.269_188_494_963_27, 66.934_723_124_404_7, -40.066_189_370_910_02, -54.667_802_628_779_68, -9.488_616_523_096_27]),
        ],
        alpha: [0.0, 0.635_812_689_582_870_4, 0.409_579_839_339_753_5, 0.976_930_672_506_071_6, 0.428_840_360_955_866_4, 1.0, 1.0, 1.0],
        d: row([0.211_937_563_194_290_14, -0.423_875_126_388_580_27, -0.338_462_712_623_592_4, 1.804_645_287_288_273_4, 2.325_825_639_765_069]),
        // y_new = stage 8's argument + k8; k8 is its difference from the order-4 solution.
        m: [A6[0], A6[1], A6[2], A6[3], A6[4], 1.0, 1.0, 1.0],
        e: row([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
        estimate_order: 5.0,
        w_method: false,
    }
};
