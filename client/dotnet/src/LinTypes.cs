// The types of Ixxat.Vci3.Bal.Lin: messages, modes, bit rates, line status. Values as IXXAT's
// lintype.h (VCI 3).
using System;

namespace Ixxat.Vci3.Bal.Lin
{
  [Flags]
  public enum LinOperatingModes : byte { Slave = 0x00, Master = 0x01, Errors = 0x02 }

  public enum LinBitrate : ushort
  {
    AutoRate = 0, MinBitrate = 1000, MaxBitrate = 20000, Undefined = 65535,
    Lin1000Bit = 1000, Lin1200Bit = 1200, Lin2400Bit = 2400, Lin4800Bit = 4800, Lin9600Bit = 9600,
    Lin10400Bit = 10400, Lin19200Bit = 19200, Lin20000Bit = 20000,
  }

  public struct LinInitLine
  {
    public LinOperatingModes OperatingMode;
    // bit/s: 1000..20000, or LinBitrate.AutoRate (a slave that takes the rate from the bus).
    public LinBitrate Bitrate;
  }

  public enum LinMessageType : byte { Data = 0, Info = 1, Error = 2, Status = 3, Wakeup = 4, Sleep = 5, TimeOverrun = 6 }

  public enum LinMsgInfoValue : byte { Start = 1, Stop = 2, Reset = 3 }

  public enum LinMsgError : byte { Bit = 1, Checksum = 2, Parity = 3, SlaveNoResponse = 4, Sync = 5, NoBus = 6, Other = 7 }

  public enum LinCtrlType : byte { Unknown = 0 }

  public struct LinMessage
  {
    uint timeStamp;
    byte protId, dataLength;
    LinMessageType type;
    bool idOnly, ecs, sor, overrun;
    ulong data;

    public uint TimeStamp { get { return timeStamp; } set { timeStamp = value; } }
    // The frame's identifier, 0..63 (the parity bits exist on the wire only).
    public byte ProtId { get { return protId; } set { protId = value; } }
    public LinMessageType MessageType { get { return type; } set { type = value; } }
    public byte DataLength
    {
      get { return dataLength; }
      set
      {
        if (value > 8) throw new VciException(Native.E_INVALIDARG, "LinMessage.DataLength " + value + " is above 8");
        dataLength = value;
      }
    }
    // Master: send the header alone (the response comes from a slave or the response table).
    public bool IdOnly { get { return idOnly; } set { idOnly = value; } }
    // The enhanced checksum of LIN 2.x (else the classic one).
    public bool ExtendedCrc { get { return ecs; } set { ecs = value; } }
    public bool SenderOfResponse { get { return sor; } }
    public bool PossibleOverrun { get { return overrun; } }

    public byte this[int index]
    {
      get { Check(index); return (byte)(data >> (8 * index)); }
      set { Check(index); data = (data & ~(0xFFUL << (8 * index))) | ((ulong)value << (8 * index)); }
    }

    static void Check(int index)
    {
      if (index < 0 || index > 7) throw new IndexOutOfRangeException("LinMessage data index " + index + " is not 0..7");
    }

    internal byte[] ToNative()
    {
      var b = new byte[Native.LinMsgSize];
      Bytes.Put32(b, 0, timeStamp);
      b[4] = protId;
      b[5] = (byte)type;
      b[6] = dataLength;
      b[7] = (byte)((ecs ? 0x01 : 0) | (idOnly ? 0x08 : 0));
      for (int i = 0; i < 8; i++) b[8 + i] = (byte)(data >> (8 * i));
      return b;
    }

    internal static LinMessage FromNative(byte[] b)
    {
      var m = new LinMessage();
      m.timeStamp = Bytes.U32(b, 0);
      m.protId = b[4];
      m.type = (LinMessageType)b[5];
      m.dataLength = Math.Min(b[6], (byte)8);
      m.ecs = (b[7] & 0x01) != 0;
      m.sor = (b[7] & 0x02) != 0;
      m.overrun = (b[7] & 0x04) != 0;
      m.idOnly = (b[7] & 0x08) != 0;
      for (int i = 0; i < 8; i++) m.data |= (ulong)b[8 + i] << (8 * i);
      return m;
    }

    public override string ToString()
    {
      var s = string.Format("{0} id=0x{1:X2} len={2} [", type, protId, dataLength);
      for (int i = 0; i < dataLength; i++) s += (i > 0 ? " " : "") + this[i].ToString("X2");
      return s + "] t=" + timeStamp;
    }
  }

  public struct LinLineStatus
  {
    internal LinOperatingModes mode;
    internal ushort bitrate;
    internal uint status;
    public LinOperatingModes OperatingMode { get { return mode; } }
    public LinBitrate Bitrate { get { return (LinBitrate)bitrate; } }
    public bool HasDataOverrun { get { return (status & 0x01) != 0; } }
    public bool IsInInitMode { get { return (status & 0x10) != 0; } }
    public override string ToString() { return string.Format("{0} {1} bit/s init={2}", mode, bitrate, IsInInitMode); }
  }
}
