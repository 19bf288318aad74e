// CanBitrate: the SJA1000's bus timing registers BTR0/BTR1 at 16 MHz, and the presets of the
// manual's table (section 4.2.4.1).
using System;

namespace Ixxat.Vci3.Bal.Can
{
  public struct CanBitrate
  {
    readonly byte btr0, btr1;

    public CanBitrate(byte btr0, byte btr1) { this.btr0 = btr0; this.btr1 = btr1; }

    public byte Btr0 { get { return btr0; } }
    public byte Btr1 { get { return btr1; } }

    public static readonly CanBitrate Empty = new CanBitrate(0, 0);
    public static readonly CanBitrate Cia10KBit = new CanBitrate(0x31, 0x1C);
    public static readonly CanBitrate Cia20KBit = new CanBitrate(0x18, 0x1C);
    public static readonly CanBitrate Cia50KBit = new CanBitrate(0x09, 0x1C);
    public static readonly CanBitrate Cia125KBit = new CanBitrate(0x03, 0x1C);
    public static readonly CanBitrate Cia250KBit = new CanBitrate(0x01, 0x1C);
    public static readonly CanBitrate Cia500KBit = new CanBitrate(0x00, 0x1C);
    public static readonly CanBitrate Cia800KBit = new CanBitrate(0x00, 0x16);
    public static readonly CanBitrate Cia1000KBit = new CanBitrate(0x00, 0x14);
    // The manual prints "CanBitrate.100KBit", which no C# identifier can be (docs/dotnet.md).
    public static readonly CanBitrate _100KBit = new CanBitrate(0x04, 0x1C);

    // The CiA rates in the order of the manual's table, for DetectBaud.
    public static CanBitrate[] CiaBitRates
    {
      get { return new[] { Cia10KBit, Cia20KBit, Cia50KBit, Cia125KBit, Cia250KBit, Cia500KBit,
                           Cia800KBit, Cia1000KBit }; }
    }

    // Time quanta per bit: SYNC + TSEG1 + TSEG2.
    public int QuantaPerBit { get { return 1 + ((btr1 & 0x0F) + 1) + (((btr1 >> 4) & 0x07) + 1); } }

    // The nominal rate in bit/s: 16 MHz / (2 * (BRP + 1) * quanta per bit).
    public int BitsPerSecond
    {
      get { return 16000000 / (2 * ((btr0 & 0x3F) + 1) * QuantaPerBit); }
    }

    // The raw CANBTP of libvcinpl2 (prescaler of the 8 MHz CAN clock, TS1 without SYNC).
    internal byte[] ToBtp()
    {
      var b = new byte[Native.BtpSize];
      Bytes.Put32(b, 0, 0x01u | ((btr1 & 0x80) != 0 ? 0x02u : 0u));  // CAN_BTMODE_RAW (| TSM)
      Bytes.Put32(b, 4, (uint)((btr0 & 0x3F) + 1));
      Bytes.Put16(b, 8, (ushort)((btr1 & 0x0F) + 1));
      Bytes.Put16(b, 10, (ushort)(((btr1 >> 4) & 0x07) + 1));
      Bytes.Put16(b, 12, (ushort)(((btr0 >> 6) & 0x03) + 1));
      return b;
    }

    internal static CanBitrate FromBtp(byte[] b, int at)
    {
      uint mode = Bytes.U32(b, at), bps = Bytes.U32(b, at + 4);
      int ts1 = Bytes.U16(b, at + 8), ts2 = Bytes.U16(b, at + 10), sjw = Bytes.U16(b, at + 12);
      if ((mode & 0x01) == 0 || bps == 0 || ts1 == 0 || ts2 == 0) return Empty;
      var btr0 = (byte)((((sjw - 1) & 0x03) << 6) | ((int)(bps - 1) & 0x3F));
      var btr1 = (byte)(((mode & 0x02) != 0 ? 0x80 : 0) | (((ts2 - 1) & 0x07) << 4) | ((ts1 - 1) & 0x0F));
      return new CanBitrate(btr0, btr1);
    }

    public override bool Equals(object o) { return o is CanBitrate && ((CanBitrate)o).btr0 == btr0 && ((CanBitrate)o).btr1 == btr1; }
    public override int GetHashCode() { return btr0 << 8 | btr1; }
    public static bool operator ==(CanBitrate a, CanBitrate b) { return a.Equals(b); }
    public static bool operator !=(CanBitrate a, CanBitrate b) { return !a.Equals(b); }
    public override string ToString()
    {
      return string.Format("BTR0=0x{0:X2} BTR1=0x{1:X2} ({2} bit/s)", btr0, btr1,
                           btr0 == 0 && btr1 == 0 ? 0 : BitsPerSecond);
    }
  }
}
